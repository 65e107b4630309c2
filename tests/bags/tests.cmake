# Test support: writes rosbag2 bags (MCAP or sqlite3) and encodes ROS 2 messages as CDR.
add_library(ssta_test_ros2_writer STATIC
  ${CMAKE_CURRENT_LIST_DIR}/support/ros2_bag_writer.cpp
  ${CMAKE_CURRENT_LIST_DIR}/support/ros_cdr_encoder.cpp)
target_include_directories(ssta_test_ros2_writer PUBLIC ${PROJECT_SOURCE_DIR}/tests ${PROJECT_SOURCE_DIR}/src)
target_link_libraries(ssta_test_ros2_writer PUBLIC ssta::mcap ssta::io PRIVATE ${SSTA_BAG_LIBS})
ssta_set_warnings(ssta_test_ros2_writer)

# A sequence as the messages a robot records, written as a ROS 1 bag with rosbag's own C++ API
# and the ROS message packages, or as a ROS 2 bag with the writer above (the bag tests and the
# command line's).
add_library(ssta_test_bag_support STATIC ${CMAKE_CURRENT_LIST_DIR}/support/bag_content.cpp)
target_link_libraries(ssta_test_bag_support PUBLIC ssta::ssta ssta::rosbag ssta_test_ros2_writer PRIVATE ${OpenCV_LIBS})
target_include_directories(ssta_test_bag_support PUBLIC ${PROJECT_SOURCE_DIR}/tests ${PROJECT_SOURCE_DIR}/src)
ssta_set_warnings(ssta_test_bag_support)

ssta_add_test(bags_test
  ${CMAKE_CURRENT_LIST_DIR}/ros2_bag_test.cpp
  ${CMAKE_CURRENT_LIST_DIR}/bag_test.cpp)
# ros2_bag_test.cpp also makes sqlite files that are no bags.
target_link_libraries(bags_test PRIVATE ssta_test_bag_support sqlite3)
