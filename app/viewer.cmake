target_sources(softbody PRIVATE ${CMAKE_CURRENT_LIST_DIR}/viewer_main.cpp)
