include(GNUInstallDirs)
include(CMakePackageConfigHelpers)

set(ssta_install_targets ${SSTA_COMPONENT_TARGETS})
foreach(module ${SSTA_MODULES})
  list(APPEND ssta_install_targets ssta_${module})
endforeach()
install(TARGETS ${ssta_install_targets} EXPORT sstaTargets
        ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR}
        LIBRARY DESTINATION ${CMAKE_INSTALL_LIBDIR}
        RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR}
        INCLUDES DESTINATION ${CMAKE_INSTALL_INCLUDEDIR})
install(DIRECTORY include/ssta DESTINATION ${CMAKE_INSTALL_INCLUDEDIR})
install(EXPORT sstaTargets NAMESPACE ssta:: DESTINATION ${CMAKE_INSTALL_LIBDIR}/cmake/ssta)
install(DIRECTORY config/ DESTINATION ${CMAKE_INSTALL_DATADIR}/ssta/config)

configure_package_config_file(cmake/sstaConfig.cmake.in
  ${CMAKE_CURRENT_BINARY_DIR}/sstaConfig.cmake
  INSTALL_DESTINATION ${CMAKE_INSTALL_LIBDIR}/cmake/ssta)
write_basic_package_version_file(${CMAKE_CURRENT_BINARY_DIR}/sstaConfigVersion.cmake
  COMPATIBILITY SameMinorVersion)
install(FILES ${CMAKE_CURRENT_BINARY_DIR}/sstaConfig.cmake
              ${CMAKE_CURRENT_BINARY_DIR}/sstaConfigVersion.cmake
              ${PROJECT_SOURCE_DIR}/cmake/FindSstaPCL.cmake
              ${PROJECT_SOURCE_DIR}/cmake/FindSstaRosbag.cmake
        DESTINATION ${CMAKE_INSTALL_LIBDIR}/cmake/ssta)
