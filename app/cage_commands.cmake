target_sources(softbody PRIVATE ${CMAKE_CURRENT_LIST_DIR}/cage_commands.cpp)
