# Sources of the eval module: the scorer behind `ssta eval` (OpenCV only in comparison_picture).
target_sources(ssta PRIVATE
  ${CMAKE_CURRENT_LIST_DIR}/class_grid.cpp
  ${CMAKE_CURRENT_LIST_DIR}/class_ids.cpp
  ${CMAKE_CURRENT_LIST_DIR}/comparison_picture.cpp
  ${CMAKE_CURRENT_LIST_DIR}/confusion_matrix.cpp
  ${CMAKE_CURRENT_LIST_DIR}/footprint_evaluator.cpp
  ${CMAKE_CURRENT_LIST_DIR}/grid_evaluator.cpp
  ${CMAKE_CURRENT_LIST_DIR}/label_evaluator.cpp
  ${CMAKE_CURRENT_LIST_DIR}/metrics_json.cpp
  ${CMAKE_CURRENT_LIST_DIR}/query_evaluator.cpp)
