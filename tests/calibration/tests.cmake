# GoogleTest suites of the calibration module (`ctest -R calib` selects them by the binary prefix).
ssta_add_test(calibration_test
  ${CMAKE_CURRENT_LIST_DIR}/stereo_calibrator_test.cpp)
