# Sources of the geometry module.
target_sources(ssta PRIVATE
  ${CMAKE_CURRENT_LIST_DIR}/normal_estimator.cpp
  ${CMAKE_CURRENT_LIST_DIR}/segmenter.cpp)
