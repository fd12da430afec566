# `ibl view`: the page's template, script, style and scene shader (viewer/) and the runtime
# shader shaders/ibl.glsl are compiled into the CLI (cli/viewer_html.c reads them), so the
# HTML it writes carries the library's own GLSL verbatim.
set(IBL_VIEWER_ASSET_NAMES ibl_viewer_template ibl_viewer_css ibl_viewer_js ibl_viewer_scene_frag ibl_viewer_ibl_glsl)
set(IBL_VIEWER_ASSET_FILES
  ${CMAKE_CURRENT_SOURCE_DIR}/viewer/viewer.html
  ${CMAKE_CURRENT_SOURCE_DIR}/viewer/viewer.css
  ${CMAKE_CURRENT_SOURCE_DIR}/viewer/viewer.js
  ${CMAKE_CURRENT_SOURCE_DIR}/viewer/scene.frag
  ${CMAKE_CURRENT_SOURCE_DIR}/shaders/ibl.glsl)
set(IBL_VIEWER_ASSETS_C ${CMAKE_CURRENT_BINARY_DIR}/viewer_assets.c)
add_custom_command(OUTPUT ${IBL_VIEWER_ASSETS_C}
  COMMAND ${CMAKE_COMMAND} -DOUT=${IBL_VIEWER_ASSETS_C} "-DNAMES=${IBL_VIEWER_ASSET_NAMES}"
          "-DFILES=${IBL_VIEWER_ASSET_FILES}" -P ${CMAKE_CURRENT_SOURCE_DIR}/viewer/embed.cmake
  DEPENDS ${IBL_VIEWER_ASSET_FILES} ${CMAKE_CURRENT_SOURCE_DIR}/viewer/embed.cmake
  COMMENT "Embedding the viewer page and shaders/ibl.glsl" VERBATIM)
target_sources(ibl PRIVATE ${IBL_VIEWER_ASSETS_C})
