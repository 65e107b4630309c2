ssta_add_test(pipeline_test
  ${CMAKE_CURRENT_LIST_DIR}/attitude_filter_test.cpp
  ${CMAKE_CURRENT_LIST_DIR}/cli_test.cpp
  ${CMAKE_CURRENT_LIST_DIR}/config_test.cpp
  ${CMAKE_CURRENT_LIST_DIR}/end_to_end_test.cpp
  ${CMAKE_CURRENT_LIST_DIR}/frame_pipeline_test.cpp
  ${CMAKE_CURRENT_LIST_DIR}/map_builder_test.cpp
  ${CMAKE_CURRENT_LIST_DIR}/real_data_test.cpp)
