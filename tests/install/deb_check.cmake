# Builds the Debian package with cpack and checks its contents and dependencies with dpkg-deb
# (the package is not installed: that would change the machine).
# -DBUILD_DIR=<build tree> -DWORK=<scratch folder> -DVERSION=<project version>
cmake_minimum_required(VERSION 3.22)

file(REMOVE_RECURSE ${WORK})
file(MAKE_DIRECTORY ${WORK})
execute_process(COMMAND cpack --config ${BUILD_DIR}/CPackConfig.cmake -G DEB -B ${WORK}
    RESULT_VARIABLE code OUTPUT_VARIABLE out ERROR_VARIABLE err)
file(GLOB debs ${WORK}/*.deb)
list(LENGTH debs count)
if(NOT code EQUAL 0 OR NOT count EQUAL 1)
    message(FATAL_ERROR "cpack failed (exit ${code}, ${count} packages):\n${out}\n${err}")
endif()

execute_process(COMMAND dpkg-deb -c ${debs} RESULT_VARIABLE code OUTPUT_VARIABLE contents)
if(NOT code EQUAL 0)
    message(FATAL_ERROR "dpkg-deb -c ${debs} failed")
endif()
foreach(f ./usr/bin/cloud-analysis ./usr/bin/scene-render
        ./usr/share/stereoscene/schema/entities.schema.json
        ./usr/share/stereoscene/assets/classes/render_classes.json
        ./usr/share/stereoscene/assets/palettes/cityscapes.json
        ./usr/share/stereoscene/assets/models/car.glb
        ./usr/share/stereoscene/samples/synthetic/left.png
        ./usr/share/stereoscene/web/viewer.js
        ./usr/share/stereoscene/web/viewer_util.js)
    if(NOT contents MATCHES " ${f}\n")
        message(FATAL_ERROR "the package lacks ${f}:\n${contents}")
    endif()
endforeach()
if(contents MATCHES " ./usr/(include|lib)/")
    message(FATAL_ERROR "the package carries headers or libraries:\n${contents}")
endif()

execute_process(COMMAND dpkg-deb -f ${debs} Package Version Depends OUTPUT_VARIABLE fields)
foreach(want "Package: stereoscene" "Version: ${VERSION}" "libopencv-core" "libegl-mesa0"
        "libgl1-mesa-dri" "libopengl0")
    string(FIND "${fields}" "${want}" at)
    if(at EQUAL -1)
        message(FATAL_ERROR "the package's control fields lack '${want}':\n${fields}")
    endif()
endforeach()
file(REMOVE_RECURSE ${WORK})
