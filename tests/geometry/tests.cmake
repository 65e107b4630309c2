ssta_add_test(geometry_test
  ${CMAKE_CURRENT_LIST_DIR}/synthetic_scene.cpp
  ${CMAKE_CURRENT_LIST_DIR}/normal_estimator_test.cpp
  ${CMAKE_CURRENT_LIST_DIR}/segmenter_test.cpp
  ${CMAKE_CURRENT_LIST_DIR}/geometry_timing_test.cpp)
# `ctest -R geometry` selects by test name, and the discovered names are the GoogleTest ones
# (NormalEstimator.*, Segmenter.*, ...), so it would find nothing: this entry runs the whole
# binary under the module's name. Redundant once ssta_add_test sets a TEST_PREFIX.
add_test(NAME geometry_test COMMAND geometry_test)
