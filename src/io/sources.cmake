# Sources of the io module.
target_sources(ssta PRIVATE
  ${CMAKE_CURRENT_LIST_DIR}/camera_calibration.cpp
  ${CMAKE_CURRENT_LIST_DIR}/file_util.cpp
  ${CMAKE_CURRENT_LIST_DIR}/image_io.cpp
  ${CMAKE_CURRENT_LIST_DIR}/yaml_reader.cpp)
target_sources(ssta PRIVATE
  ${CMAKE_CURRENT_LIST_DIR}/sequence.cpp
  ${CMAKE_CURRENT_LIST_DIR}/kitti_raw.cpp)
