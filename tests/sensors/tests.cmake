ssta_add_test(sensors_test
  ${CMAKE_CURRENT_LIST_DIR}/attitude_filter_test.cpp)
