# Sources of the pipeline module.
target_sources(ssta PRIVATE
  ${CMAKE_CURRENT_LIST_DIR}/attitude_filter.cpp
  ${CMAKE_CURRENT_LIST_DIR}/bench.cpp
  ${CMAKE_CURRENT_LIST_DIR}/config.cpp
  ${CMAKE_CURRENT_LIST_DIR}/frame_pipeline.cpp
  ${CMAKE_CURRENT_LIST_DIR}/gravity_provider.cpp
  ${CMAKE_CURRENT_LIST_DIR}/map_builder.cpp
  ${CMAKE_CURRENT_LIST_DIR}/ordered_worker.cpp
  ${CMAKE_CURRENT_LIST_DIR}/frame_report.cpp
  ${CMAKE_CURRENT_LIST_DIR}/sequence_classifier.cpp)
