ssta_add_test(io_test
  ${CMAKE_CURRENT_LIST_DIR}/camera_calibration_test.cpp
  ${CMAKE_CURRENT_LIST_DIR}/image_codec_test.cpp
  ${CMAKE_CURRENT_LIST_DIR}/text_parsers_test.cpp
  ${CMAKE_CURRENT_LIST_DIR}/sequence_test.cpp
  ${CMAKE_CURRENT_LIST_DIR}/kitti_raw_test.cpp)
