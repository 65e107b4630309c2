ssta_add_test(synth_test ${CMAKE_CURRENT_LIST_DIR}/synth_test.cpp)
