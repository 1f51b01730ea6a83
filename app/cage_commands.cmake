target_sources(softbody PRIVATE ${CMAKE_CURRENT_LIST_DIR}/cage_commands.cpp)
# softbody_sim links softbody_cage publicly; link it here too so the commands also build on
# their own (e.g. a cage-only build).
target_link_libraries(softbody PRIVATE softbody_cage)
