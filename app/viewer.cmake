# The viewer part of the softbody executable (included from app/CMakeLists.txt). Without
# SOFTBODY_BUILD_VIEWER only the headless fallback is built.
target_sources(softbody PRIVATE
  ${CMAKE_CURRENT_LIST_DIR}/viewer_main.cpp
  ${CMAKE_CURRENT_LIST_DIR}/viewer_headless.cpp)
target_link_libraries(softbody PRIVATE nlohmann_json::nlohmann_json)
if(SOFTBODY_BUILD_VIEWER)
  target_sources(softbody PRIVATE
    ${CMAKE_CURRENT_LIST_DIR}/viewer_app.cpp
    ${CMAKE_CURRENT_LIST_DIR}/viewer_bodies.cpp
    ${CMAKE_CURRENT_LIST_DIR}/viewer_input.cpp
    ${CMAKE_CURRENT_LIST_DIR}/viewer_params.cpp
    ${CMAKE_CURRENT_LIST_DIR}/viewer_plots.cpp
    ${CMAKE_CURRENT_LIST_DIR}/viewer_ui.cpp
    ${CMAKE_CURRENT_LIST_DIR}/viewer_stats.cpp
    ${CMAKE_CURRENT_LIST_DIR}/stats_file_writer.cpp
    ${CMAKE_CURRENT_LIST_DIR}/viewer_embedding.cpp
    ${CMAKE_CURRENT_LIST_DIR}/viewer_folds.cpp
  )
  target_compile_definitions(softbody PRIVATE SOFTBODY_HAVE_VIEWER=1)
  target_link_libraries(softbody PRIVATE softbody_render glfw PkgConfig::IMGUI PkgConfig::STB)
endif()
