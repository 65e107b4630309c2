# Sources of the synth module.
target_sources(ssta PRIVATE ${CMAKE_CURRENT_LIST_DIR}/scene.cpp)
target_sources(ssta PRIVATE ${CMAKE_CURRENT_LIST_DIR}/scene_catalogue.cpp)
target_sources(ssta PRIVATE ${CMAKE_CURRENT_LIST_DIR}/stereo_renderer.cpp)
target_sources(ssta PRIVATE ${CMAKE_CURRENT_LIST_DIR}/vehicle_trajectory.cpp)
target_sources(ssta PRIVATE ${CMAKE_CURRENT_LIST_DIR}/synth_options.cpp)
target_sources(ssta PRIVATE ${CMAKE_CURRENT_LIST_DIR}/sequence_synthesizer.cpp)
# The renderer spreads rows over std::thread workers.
find_package(Threads REQUIRED)
target_link_libraries(ssta PRIVATE Threads::Threads)
