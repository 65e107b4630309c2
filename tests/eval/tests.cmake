# GoogleTest suites of the eval module. Suite names start with "eval_" so that
# `ctest -R eval` selects them (ctest matches the discovered test names, not the binary).
ssta_add_test(eval_test
  ${CMAKE_CURRENT_LIST_DIR}/confusion_matrix_test.cpp
  ${CMAKE_CURRENT_LIST_DIR}/disparity_evaluator_test.cpp
  ${CMAKE_CURRENT_LIST_DIR}/json_writer_test.cpp
  ${CMAKE_CURRENT_LIST_DIR}/label_evaluator_test.cpp
  ${CMAKE_CURRENT_LIST_DIR}/grid_evaluator_test.cpp
  ${CMAKE_CURRENT_LIST_DIR}/query_evaluator_test.cpp
  ${CMAKE_CURRENT_LIST_DIR}/footprint_evaluator_test.cpp
  ${CMAKE_CURRENT_LIST_DIR}/eval_cli_test.cpp)
