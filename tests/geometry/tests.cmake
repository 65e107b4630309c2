ssta_add_test(geometry_test
  ${CMAKE_CURRENT_LIST_DIR}/synthetic_scene.cpp
  ${CMAKE_CURRENT_LIST_DIR}/normal_estimator_test.cpp
  ${CMAKE_CURRENT_LIST_DIR}/segmenter_test.cpp)
