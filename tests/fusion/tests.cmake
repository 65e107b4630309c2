ssta_add_test(fusion_test
  ${CMAKE_CURRENT_LIST_DIR}/frame_points_test.cpp)
