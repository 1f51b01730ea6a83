target_sources(softbody PRIVATE ${CMAKE_CURRENT_LIST_DIR}/cage_commands.cpp
  ${CMAKE_CURRENT_LIST_DIR}/ffd_command.cpp ${CMAKE_CURRENT_LIST_DIR}/command_line.cpp)
target_link_libraries(softbody PRIVATE softbody_cage softbody_mesh)
