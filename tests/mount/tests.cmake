ssta_add_test(mount_test
  ${CMAKE_CURRENT_LIST_DIR}/mount_refiner_test.cpp)
