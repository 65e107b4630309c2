# The `ssta` command line: every command, bad input, and faults (signals, full disks).
ssta_add_test(cli_test
  ${CMAKE_CURRENT_LIST_DIR}/bad_input_test.cpp
  ${CMAKE_CURRENT_LIST_DIR}/cli_test.cpp
  ${CMAKE_CURRENT_LIST_DIR}/fault_test.cpp
  ${CMAKE_CURRENT_LIST_DIR}/bag_cli_test.cpp
  ${CMAKE_CURRENT_LIST_DIR}/map_writers_test.cpp)
target_link_libraries(cli_test PRIVATE ssta_test_bag_support)
