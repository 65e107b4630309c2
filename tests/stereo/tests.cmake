ssta_add_test(stereo_test
  ${CMAKE_CURRENT_LIST_DIR}/triangulator_test.cpp
  ${CMAKE_CURRENT_LIST_DIR}/stereo_matcher_test.cpp
  ${CMAKE_CURRENT_LIST_DIR}/ratio_filter_test.cpp
  ${CMAKE_CURRENT_LIST_DIR}/rectifier_test.cpp)
