ssta_add_test(mapping_test
  ${CMAKE_CURRENT_LIST_DIR}/trav_octree_test.cpp
  ${CMAKE_CURRENT_LIST_DIR}/map_file_test.cpp
  ${CMAKE_CURRENT_LIST_DIR}/fusion_test.cpp
  ${CMAKE_CURRENT_LIST_DIR}/queries_test.cpp
  ${CMAKE_CURRENT_LIST_DIR}/map_export_test.cpp
  ${CMAKE_CURRENT_LIST_DIR}/map_mcap_export_test.cpp
  ${CMAKE_CURRENT_LIST_DIR}/surface_judgement_test.cpp
  ${CMAKE_CURRENT_LIST_DIR}/sensor_path_test.cpp
  ${CMAKE_CURRENT_LIST_DIR}/map_merge_test.cpp
  ${CMAKE_CURRENT_LIST_DIR}/map_diff_test.cpp
  ${CMAKE_CURRENT_LIST_DIR}/safe_fusion_test.cpp
  ${CMAKE_CURRENT_LIST_DIR}/vehicle_attitude_test.cpp)
# The tests look inside the octree (src/mapping/trav_octree.h) and read exports back.
target_include_directories(mapping_test SYSTEM PRIVATE ${OCTOMAP_INCLUDE_DIRS})
target_link_libraries(mapping_test PRIVATE ${OCTOMAP_LIBRARIES} yaml-cpp)
