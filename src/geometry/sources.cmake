# Sources of the geometry module.
target_sources(ssta PRIVATE
  ${CMAKE_CURRENT_LIST_DIR}/normal_estimator.cpp
  ${CMAKE_CURRENT_LIST_DIR}/segmenter.cpp)
# The per-row kernels (eigen solve, window sums, join tests) are branch-free loops; GCC only
# turns their selects into vector blends when floating-point comparisons may not trap (we never
# enable FP exceptions).
if(CMAKE_CXX_COMPILER_ID MATCHES "GNU|Clang")
  set_source_files_properties(
    ${CMAKE_CURRENT_LIST_DIR}/normal_estimator.cpp ${CMAKE_CURRENT_LIST_DIR}/segmenter.cpp
    PROPERTIES COMPILE_OPTIONS "-fno-trapping-math")
endif()
