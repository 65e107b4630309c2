ssta_add_test(analysis_test
  ${CMAKE_CURRENT_LIST_DIR}/surface_analyzer_test.cpp
  ${CMAKE_CURRENT_LIST_DIR}/label_refinements_test.cpp)
