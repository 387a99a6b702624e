# The browser viewer's static files, gathered in ${SCENE_VIEWER_WEB_DIR} where `scene-render html`
# copies them from: the page's own sources (this folder) and three.js 0.160 with its orbit
# controls and glTF loader, bundled by esbuild into one classic script (file:// pages cannot
# import ES modules). three.js and esbuild come from the npm registry, pinned in
# scripts/npm/package-lock.json and installed by scripts/install-deps.sh (not committed).
set(SCENE_VIEWER_WEB_DIR ${CMAKE_CURRENT_BINARY_DIR}/web)
set(STEREOSCENE_NODE_MODULES ${PROJECT_SOURCE_DIR}/scripts/npm/node_modules CACHE INTERNAL
    "npm packages of the viewer and its browser tests")
set(_web_outputs)
foreach(file index.html viewer.css viewer_util.js viewer_models.js viewer_panel.js viewer_drive.js
        viewer.js)
    add_custom_command(OUTPUT ${SCENE_VIEWER_WEB_DIR}/${file}
        COMMAND ${CMAKE_COMMAND} -E copy ${CMAKE_CURRENT_LIST_DIR}/${file}
            ${SCENE_VIEWER_WEB_DIR}/${file}
        DEPENDS ${CMAKE_CURRENT_LIST_DIR}/${file}
        COMMENT "Copying viewer ${file}" VERBATIM)
    list(APPEND _web_outputs ${SCENE_VIEWER_WEB_DIR}/${file})
endforeach()
set(_esbuild ${STEREOSCENE_NODE_MODULES}/.bin/esbuild)
find_program(STEREOSCENE_NODE NAMES node nodejs)
if(STEREOSCENE_NODE AND EXISTS ${_esbuild} AND EXISTS ${STEREOSCENE_NODE_MODULES}/three/package.json)
    add_custom_command(OUTPUT ${SCENE_VIEWER_WEB_DIR}/three.min.js
        COMMAND ${CMAKE_COMMAND} -E env NODE_PATH=${STEREOSCENE_NODE_MODULES}
            ${_esbuild} ${CMAKE_CURRENT_LIST_DIR}/three_entry.js --bundle --format=iife
            --global-name=THREE --minify --legal-comments=inline --log-level=warning
            --outfile=${SCENE_VIEWER_WEB_DIR}/three.min.js
        DEPENDS ${CMAKE_CURRENT_LIST_DIR}/three_entry.js
            ${STEREOSCENE_NODE_MODULES}/three/package.json
        COMMENT "Bundling three.js for the viewer" VERBATIM)
    list(APPEND _web_outputs ${SCENE_VIEWER_WEB_DIR}/three.min.js)
    set(STEREOSCENE_VIEWER_THREE ON CACHE INTERNAL "three.js bundle built for the viewer")
else()
    message(STATUS "three.js or esbuild not installed in ${STEREOSCENE_NODE_MODULES} "
        "(scripts/install-deps.sh): scene-render html will say so, browser tests skip")
    set(STEREOSCENE_VIEWER_THREE OFF CACHE INTERNAL "three.js bundle built for the viewer")
endif()
add_custom_target(scene_viewer_web ALL DEPENDS ${_web_outputs})
