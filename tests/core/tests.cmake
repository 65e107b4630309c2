ssta_add_test(core_test
  ${CMAKE_CURRENT_LIST_DIR}/classes_test.cpp
  ${CMAKE_CURRENT_LIST_DIR}/parallel_pair_test.cpp
  ${CMAKE_CURRENT_LIST_DIR}/vehicle_options_test.cpp)
