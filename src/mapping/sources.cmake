# Sources of the mapping module (OctoMap-backed traversability map). Only these files include
# OctoMap headers.
target_sources(ssta PRIVATE
  ${CMAKE_CURRENT_LIST_DIR}/map_options.cpp
  ${CMAKE_CURRENT_LIST_DIR}/trav_octree.cpp
  ${CMAKE_CURRENT_LIST_DIR}/traversability_map.cpp
  ${CMAKE_CURRENT_LIST_DIR}/map_file.cpp
  ${CMAKE_CURRENT_LIST_DIR}/map_export.cpp)
