# Sources of the stereo module. pcl_stereo.cpp is the only file that includes PCL headers.
target_sources(ssta PRIVATE
  ${CMAKE_CURRENT_LIST_DIR}/rectifier.cpp
  ${CMAKE_CURRENT_LIST_DIR}/stereo_matcher.cpp
  ${CMAKE_CURRENT_LIST_DIR}/pcl_stereo.cpp
  ${CMAKE_CURRENT_LIST_DIR}/ratio_filter.cpp
  ${CMAKE_CURRENT_LIST_DIR}/triangulator.cpp)
