ssta_add_test(pipeline_test
  ${CMAKE_CURRENT_LIST_DIR}/config_test.cpp
  ${CMAKE_CURRENT_LIST_DIR}/frame_pipeline_test.cpp
  ${CMAKE_CURRENT_LIST_DIR}/label_rules_test.cpp
  ${CMAKE_CURRENT_LIST_DIR}/map_builder_test.cpp
  ${CMAKE_CURRENT_LIST_DIR}/mount_calibration_test.cpp
  ${CMAKE_CURRENT_LIST_DIR}/online_refinement_test.cpp
  ${CMAKE_CURRENT_LIST_DIR}/real_data_test.cpp)
