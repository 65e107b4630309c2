ssta_add_test(files_test
  ${CMAKE_CURRENT_LIST_DIR}/file_util_test.cpp
  ${CMAKE_CURRENT_LIST_DIR}/png_file_test.cpp)
