# CLI tests of `scene-render sensors`: run the real binary through tests/cli/expect.sh, each
# into its own output folder, which must hold exactly the files named (or nothing after a
# failure). Included from tests/cli/CMakeLists.txt.
include_guard(GLOBAL)
if(NOT TARGET scene-render)
    return()
endif()
set(_sensors_out ${CMAKE_CURRENT_BINARY_DIR}/sensors_cli_out)
set(_sensors_scene ${PROJECT_SOURCE_DIR}/samples/rendered/scenes/thesis-one-car.json)
set(_sensors_bad ${PROJECT_SOURCE_DIR}/tests/scene_viewer/data/bad_width.json)

function(sensors_cli_test name folder)
    cmake_parse_arguments(T "" "CODE;STDERR;FILES" "ARGS" ${ARGN})
    set(checks --code ${T_CODE} --folder ${_sensors_out}/${folder})
    if(DEFINED T_STDERR)
        list(APPEND checks --stderr "${T_STDERR}")
    endif()
    if(DEFINED T_FILES)
        list(APPEND checks --files "${T_FILES}")
    endif()
    add_test(NAME "scene-render sensors ${name}" COMMAND bash ${STEREOSCENE_EXPECT} ${checks} --
        $<TARGET_FILE:scene-render> ${T_ARGS})
endfunction()

sensors_cli_test("on an invalid scene exits 1 and writes nothing" bad
    ARGS sensors ${_sensors_bad} --out ${_sensors_out}/bad CODE 1
    STDERR "error: [^\n]*bad_width.json: invalid entity file: /entities/1/W: ")
sensors_cli_test("on a missing scene exits 1 and writes nothing" missing
    ARGS sensors ${_sensors_out}/none.json --out ${_sensors_out}/missing CODE 1
    STDERR "cannot read entity file")
sensors_cli_test("with a frame name holding a folder exits 2 and writes nothing" frame
    ARGS sensors ${_sensors_scene} --out ${_sensors_out}/frame --frame a/b CODE 2
    STDERR "--frame")
sensors_cli_test("with a zero baseline exits 2 and writes nothing" baseline
    ARGS sensors ${_sensors_scene} --out ${_sensors_out}/baseline --baseline 0 CODE 2
    STDERR "baseline_m")
sensors_cli_test("without --out exits 2" noout ARGS sensors ${_sensors_scene} CODE 2)
sensors_cli_test("writes the KITTI layout" good
    ARGS sensors ${_sensors_scene} --out ${_sensors_out}/good --size 310x94 --frame 000007 CODE 0
    FILES "image_2/000007.png|image_3/000007.png|semantic_rgb/000007.png|instance/000007.png|disp_occ_0/000007.png|depth/000007.png|visibility/000007.json|calib/calib_cam_to_cam.txt")
sensors_cli_test("takes its rig from a KITTI calibration file" rig
    ARGS sensors ${_sensors_scene} --out ${_sensors_out}/rig
    --rig ${PROJECT_SOURCE_DIR}/samples/rendered/thesis-one-car/calib/calib_cam_to_cam.txt CODE 0
    FILES "image_2/000000.png|image_3/000000.png|semantic_rgb/000000.png|instance/000000.png|disp_occ_0/000000.png|depth/000000.png|visibility/000000.json|calib/calib_cam_to_cam.txt")
sensors_cli_test("with an unreadable rig file exits 1 and writes nothing" badrig
    ARGS sensors ${_sensors_scene} --out ${_sensors_out}/badrig --rig ${_sensors_bad} CODE 1
    STDERR "invalid rig: P_rect_02: missing")
