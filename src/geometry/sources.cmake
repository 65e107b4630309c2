# Sources of the geometry module.
target_sources(ssta PRIVATE
  ${CMAKE_CURRENT_LIST_DIR}/normal_estimator.cpp
  ${CMAKE_CURRENT_LIST_DIR}/segmenter.cpp)
# The covariance eigen solve is a branch-free loop over a row; GCC only turns its selects into
# vector blends when floating-point comparisons may not trap (we never enable FP exceptions).
if(CMAKE_CXX_COMPILER_ID MATCHES "GNU|Clang")
  set_source_files_properties(${CMAKE_CURRENT_LIST_DIR}/normal_estimator.cpp
    PROPERTIES COMPILE_OPTIONS "-fno-trapping-math")
endif()
