# Rendered sequences through the whole chain (synth -> classify / build-map -> export -> eval),
# and the golden outputs that pin the shipped defaults byte for byte.
ssta_add_test(end_to_end_test
  ${CMAKE_CURRENT_LIST_DIR}/end_to_end_test.cpp
  ${CMAKE_CURRENT_LIST_DIR}/golden_output_test.cpp
  ${CMAKE_CURRENT_LIST_DIR}/fleet_merge_test.cpp)
