# Rendered sequences through the whole chain (synth -> classify / build-map -> export -> eval),
# and the golden outputs that pin the shipped defaults byte for byte.
# Not in sanitizer builds: these fuse tens of frames to check accuracy figures and bytes, and take
# 20x their Release time instrumented (over CI's limit); the code they run is the code the
# pipeline, mapping and CLI tests run there on a few frames each.
if(NOT SSTA_SANITIZE AND NOT SSTA_SANITIZE_THREAD)
  ssta_add_test(end_to_end_test
    ${CMAKE_CURRENT_LIST_DIR}/end_to_end_test.cpp
    ${CMAKE_CURRENT_LIST_DIR}/golden_output_test.cpp
    ${CMAKE_CURRENT_LIST_DIR}/fleet_merge_test.cpp
    ${CMAKE_CURRENT_LIST_DIR}/map_diff_drive_test.cpp)
endif()
