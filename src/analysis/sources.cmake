# Sources of the analysis module.
target_sources(ssta PRIVATE
  ${CMAKE_CURRENT_LIST_DIR}/vehicle_options.cpp)
target_sources(ssta PRIVATE
  ${CMAKE_CURRENT_LIST_DIR}/surface_analyzer.cpp)
