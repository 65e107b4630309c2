ssta_add_test(bench_test ${CMAKE_CURRENT_LIST_DIR}/bench_test.cpp)
