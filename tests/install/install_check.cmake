# Installs the build to a temporary prefix, moves the install elsewhere, and runs both tools
# from an unrelated folder on the installed sample: cloud-analysis makes an entity file,
# scene-render draws it. Then it takes files out of the moved install to prove that the tools
# read the assets of the install they run from (not the source tree).
# -DBUILD_DIR=<build tree> -DWORK=<scratch folder>
cmake_minimum_required(VERSION 3.22)

function(run)
    cmake_parse_arguments(R "" "CODE;STDERR;DIR" "COMMAND" ${ARGN})
    execute_process(COMMAND ${R_COMMAND} WORKING_DIRECTORY ${R_DIR}
        RESULT_VARIABLE code OUTPUT_VARIABLE out ERROR_VARIABLE err)
    if(NOT code STREQUAL R_CODE)
        message(FATAL_ERROR "${R_COMMAND}: exit ${code}, expected ${R_CODE}\n${out}\n${err}")
    endif()
    if(DEFINED R_STDERR AND NOT err MATCHES "${R_STDERR}")
        message(FATAL_ERROR "${R_COMMAND}: stderr does not match '${R_STDERR}': ${err}")
    endif()
endfunction()

file(REMOVE_RECURSE ${WORK})
file(MAKE_DIRECTORY ${WORK}/elsewhere)
run(COMMAND ${CMAKE_COMMAND} --install ${BUILD_DIR} --prefix ${WORK}/first CODE 0 DIR ${WORK})
file(RENAME ${WORK}/first ${WORK}/moved)

set(bin ${WORK}/moved/bin)
set(share ${WORK}/moved/share/stereoscene)
set(sample ${share}/samples/synthetic)
foreach(f bin/cloud-analysis bin/scene-render share/stereoscene/schema/entities.schema.json
        share/stereoscene/assets/classes/render_classes.json
        share/stereoscene/assets/palettes/cityscapes.json share/stereoscene/assets/models/car.glb)
    if(NOT EXISTS ${WORK}/moved/${f})
        message(FATAL_ERROR "the install lacks ${f}")
    endif()
endforeach()

set(analyse ${bin}/cloud-analysis --left ${sample}/left.png --right ${sample}/right.png
    --semantic ${sample}/semantic.png --calib ${sample}/calib.yaml --frame synthetic-street)
run(COMMAND ${analyse} -o entities.json CODE 0 DIR ${WORK}/elsewhere)
file(READ ${WORK}/elsewhere/entities.json got)
file(READ ${sample}/expected_entities.json expected)
string(JSON got_count LENGTH "${got}" entities)
string(JSON expected_count LENGTH "${expected}" entities)
if(NOT got_count EQUAL expected_count OR got_count EQUAL 0)
    message(FATAL_ERROR "${got_count} entities, the sample expects ${expected_count}")
endif()
run(COMMAND ${bin}/scene-render entities.json -o render.png --size 160x90 CODE 0
    DIR ${WORK}/elsewhere)
file(READ ${WORK}/elsewhere/render.png magic LIMIT 4 HEX)
if(NOT magic STREQUAL "89504e47")
    message(FATAL_ERROR "render.png is not a PNG")
endif()

# The browser viewer's folder from the install's web files (three.js is bundled only where npm
# installed it: scripts/install-deps.sh).
if(VIEWER_THREE)
    run(COMMAND ${bin}/scene-render html entities.json --out viewer CODE 0 DIR ${WORK}/elsewhere)
    if(NOT EXISTS ${WORK}/elsewhere/viewer/index.html)
        message(FATAL_ERROR "scene-render html wrote no index.html")
    endif()
endif()

# Without the moved install's palette and class table the tools fail naming those files.
file(REMOVE ${share}/assets/palettes/cityscapes.json ${share}/assets/classes/render_classes.json)
run(COMMAND ${analyse} -o again.json CODE 1 DIR ${WORK}/elsewhere
    STDERR "${share}/assets/palettes/cityscapes.json")
run(COMMAND ${bin}/scene-render entities.json -o again.png CODE 1 DIR ${WORK}/elsewhere
    STDERR "${share}/assets/classes/render_classes.json")
file(REMOVE_RECURSE ${WORK})
