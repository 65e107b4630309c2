# Sources of the calibration module: `ssta calibrate-stereo` (OpenCV calib3d inside the .cpp files).
target_sources(ssta PRIVATE
  ${CMAKE_CURRENT_LIST_DIR}/board_detection.cpp
  ${CMAKE_CURRENT_LIST_DIR}/calibration_inputs.cpp
  ${CMAKE_CURRENT_LIST_DIR}/calibration_report.cpp
  ${CMAKE_CURRENT_LIST_DIR}/rectification_check.cpp
  ${CMAKE_CURRENT_LIST_DIR}/stereo_calibrator.cpp)
