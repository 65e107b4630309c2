# Writes ROS 1 bags with rosbag's own C++ API and the ROS message packages, for the bag tests.
add_library(ssta_test_bag_support STATIC ${CMAKE_CURRENT_LIST_DIR}/support/bag_content.cpp)
target_link_libraries(ssta_test_bag_support PUBLIC ssta::ssta ssta::rosbag)
target_include_directories(ssta_test_bag_support PUBLIC ${PROJECT_SOURCE_DIR}/tests ${PROJECT_SOURCE_DIR}/src)
ssta_set_warnings(ssta_test_bag_support)

ssta_add_test(io_test
  ${CMAKE_CURRENT_LIST_DIR}/camera_calibration_test.cpp
  ${CMAKE_CURRENT_LIST_DIR}/file_util_test.cpp
  ${CMAKE_CURRENT_LIST_DIR}/text_parsers_test.cpp
  ${CMAKE_CURRENT_LIST_DIR}/sequence_test.cpp
  ${CMAKE_CURRENT_LIST_DIR}/kitti_raw_test.cpp
  ${CMAKE_CURRENT_LIST_DIR}/bag_test.cpp)
target_link_libraries(io_test PRIVATE ssta_test_bag_support)
