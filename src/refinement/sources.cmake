target_sources(ssta PRIVATE
  ${CMAKE_CURRENT_LIST_DIR}/refinement_options.cpp
  ${CMAKE_CURRENT_LIST_DIR}/ground_evidence.cpp
  ${CMAKE_CURRENT_LIST_DIR}/mount_refiner.cpp
  ${CMAKE_CURRENT_LIST_DIR}/online_mount_refiner.cpp
  ${CMAKE_CURRENT_LIST_DIR}/mount_calibration.cpp)
