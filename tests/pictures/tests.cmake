ssta_add_test(pictures_test
  ${CMAKE_CURRENT_LIST_DIR}/map_picture_test.cpp)
