# CLI tests of scene-render: run the real binary through tests/cli/expect.sh. Each test writes
# into its own folder so parallel runs do not see each other's temporary files.
include_guard(GLOBAL)

set(_render_out ${CMAKE_CURRENT_BINARY_DIR}/render_cli_out)
set(_street ${PROJECT_SOURCE_DIR}/samples/baselines/street.json)
set(_bad ${PROJECT_SOURCE_DIR}/tests/scene_viewer/data/bad_width.json)
file(MAKE_DIRECTORY ${_render_out})

function(render_cli_test name)
    cmake_parse_arguments(T "" "CODE;STDERR;STDOUT;OUTPUT;OUTPUT_EXISTS;MAGIC" "ARGS" ${ARGN})
    set(checks --code ${T_CODE})
    foreach(key STDERR STDOUT OUTPUT MAGIC)
        if(DEFINED T_${key})
            string(TOLOWER ${key} flag)
            list(APPEND checks --${flag} "${T_${key}}")
        endif()
    endforeach()
    if(DEFINED T_OUTPUT_EXISTS)
        list(APPEND checks --exists ${T_OUTPUT_EXISTS})
    endif()
    add_test(NAME "scene-render ${name}" COMMAND bash ${STEREOSCENE_EXPECT} ${checks} --
        $<TARGET_FILE:scene-render> ${T_ARGS})
endfunction()

render_cli_test("--help exits 0 and names the views" ARGS --help CODE 0
    STDOUT "--view")
render_cli_test("--version exits 0" ARGS --version CODE 0 STDOUT "scene-render")
render_cli_test("a bad flag exits 2" ARGS --no-such-flag CODE 2)
render_cli_test("an unknown view exits 2" ARGS ${_street} --view top -o ${_render_out}/top/out.png
    CODE 2 STDERR "--view" OUTPUT ${_render_out}/top/out.png OUTPUT_EXISTS 0)
render_cli_test("a zero image size exits 2" ARGS ${_street} --size 0x10
    -o ${_render_out}/zero/out.png CODE 2 STDERR "--size" OUTPUT ${_render_out}/zero/out.png
    OUTPUT_EXISTS 0)
render_cli_test("an absurd image size exits 2" ARGS ${_street} --size 20000x100
    -o ${_render_out}/huge/out.png CODE 2 STDERR "16384" OUTPUT ${_render_out}/huge/out.png
    OUTPUT_EXISTS 0)
render_cli_test("an invalid entity file exits 1 naming the pointer and leaves no output"
    ARGS ${_bad} -o ${_render_out}/bad/out.png CODE 1
    STDERR "error: [^\n]*bad_width.json: invalid entity file: /entities/1/W: "
    OUTPUT ${_render_out}/bad/out.png OUTPUT_EXISTS 0)
render_cli_test("a missing entity file exits 1" ARGS ${_render_out}/none.json
    -o ${_render_out}/none/out.png CODE 1 STDERR "cannot read entity file"
    OUTPUT ${_render_out}/none/out.png OUTPUT_EXISTS 0)
render_cli_test("a missing point cloud exits 1 before rendering" ARGS ${_street}
    --cloud ${_render_out}/none.ply -o ${_render_out}/nocloud/out.png CODE 1 STDERR "--cloud"
    OUTPUT ${_render_out}/nocloud/out.png OUTPUT_EXISTS 0)
render_cli_test("--info prints the GL renderer" ARGS --info CODE 0 STDOUT "GL renderer: .+")
foreach(view camera chase bev)
    render_cli_test("renders the street sample in the ${view} view" ARGS ${_street}
        --view ${view} --size 320x180 -o ${_render_out}/street_${view}/out.png CODE 0
        OUTPUT ${_render_out}/street_${view}/out.png OUTPUT_EXISTS 1)
endforeach()
render_cli_test("renders a free view in semantic shading" ARGS ${_street} --view free
    --eye 0,-20,-5 --target 0,0,20 --fov 50 --shading semantic --size 200x120
    -o ${_render_out}/street_free/out.png CODE 0 OUTPUT ${_render_out}/street_free/out.png
    OUTPUT_EXISTS 1)
render_cli_test("--eye without a free view exits 2" ARGS ${_street} --eye 0,0,0
    -o ${_render_out}/eye/out.png CODE 2 STDERR "--eye")
render_cli_test("grid renders two entity files into one labelled figure" ARGS grid
    --inputs ${_street} ${_street} --labels A B --view bev --size 200x200
    -o ${_render_out}/grid/out.png CODE 0 OUTPUT ${_render_out}/grid/out.png OUTPUT_EXISTS 1)
render_cli_test("grid with a label count that differs exits 2" ARGS grid
    --inputs ${_street} ${_street} --labels A -o ${_render_out}/grid2/out.png CODE 2
    STDERR "--labels" OUTPUT ${_render_out}/grid2/out.png OUTPUT_EXISTS 0)
render_cli_test("'-' writes the PNG to stdout" ARGS ${_street} --size 64x32 -o - CODE 0
    STDOUT "PNG")
render_cli_test("bench times a short run and prints a row per antialiasing and shading"
    ARGS bench --frames 2 --entities 5 --size 160x90 CODE 0
    STDOUT "ms/frame.*\nlit fxaa .*\nlit msaa 4 .*\nlit none .*\nsemantic ")
foreach(aa fxaa msaa none)
    render_cli_test("renders the street sample with --antialias ${aa}" ARGS ${_street}
        --view chase --size 160x90 --antialias ${aa} -o ${_render_out}/aa_${aa}/out.png CODE 0
        OUTPUT ${_render_out}/aa_${aa}/out.png OUTPUT_EXISTS 1)
endforeach()
render_cli_test("an unknown --antialias exits 2 naming the flag" ARGS ${_street}
    --antialias ssaa -o ${_render_out}/aa_bad/out.png CODE 2
    STDERR "error: --antialias: .*unknown antialiasing 'ssaa'" OUTPUT ${_render_out}/aa_bad/out.png
    OUTPUT_EXISTS 0)
render_cli_test("--msaa 4 with --antialias fxaa exits 2 naming --msaa" ARGS ${_street}
    --antialias fxaa --msaa 4 -o ${_render_out}/aa_fxaa_msaa/out.png CODE 2
    STDERR "error: --msaa: .*contradicts --antialias fxaa"
    OUTPUT ${_render_out}/aa_fxaa_msaa/out.png OUTPUT_EXISTS 0)
render_cli_test("--antialias msaa with --msaa 0 exits 2 naming --msaa" ARGS ${_street}
    --antialias msaa --msaa 0 -o ${_render_out}/aa_msaa0/out.png CODE 2 STDERR "error: --msaa: "
    OUTPUT ${_render_out}/aa_msaa0/out.png OUTPUT_EXISTS 0)
render_cli_test("--antialias fxaa with semantic shading exits 2" ARGS ${_street}
    --shading semantic --antialias fxaa -o ${_render_out}/aa_semantic/out.png CODE 2
    STDERR "error: --antialias: .*lit shading only" OUTPUT ${_render_out}/aa_semantic/out.png
    OUTPUT_EXISTS 0)
render_cli_test("--glb exports the scene as binary glTF without an image" ARGS ${_street}
    --glb ${_render_out}/glb/out.glb CODE 0 OUTPUT ${_render_out}/glb/out.glb OUTPUT_EXISTS 1
    MAGIC 676c5446)
render_cli_test("a class without a model is drawn as a box with one warning" ARGS
    ${PROJECT_SOURCE_DIR}/tests/scene_viewer/data/street_unmodelled.json --size 160x90
    -o ${_render_out}/unmodelled/out.png CODE 0
    STDERR "^scene-render: warning: no model for class 'train'[^\n]*\n$"
    OUTPUT ${_render_out}/unmodelled/out.png OUTPUT_EXISTS 1)
render_cli_test("a class the palette does not know is a magenta box and the warning says so" ARGS
    ${PROJECT_SOURCE_DIR}/tests/scene_viewer/data/street_unknown_class.json --size 160x90
    -o ${_render_out}/unknown_class/out.png CODE 0
    STDERR "^scene-render: warning: no model for class 'hovercraft', drawn as a box in magenta [^\n]*\n$"
    OUTPUT ${_render_out}/unknown_class/out.png OUTPUT_EXISTS 1)
if(STEREOSCENE_VIEWER_THREE)
    render_cli_test("html writes the viewer folder of the street sample" ARGS html ${_street}
        --out ${_render_out}/html --cloud ${PROJECT_SOURCE_DIR}/tests/scene_viewer/data/tiny_cloud.ply
        CODE 0 OUTPUT ${_render_out}/html/index.html OUTPUT_EXISTS 1 MAGIC 3c21646f6374797065)
endif()
render_cli_test("html with a missing entity file exits 1 and writes no folder" ARGS html
    ${_render_out}/none.json --out ${_render_out}/html_none CODE 1 STDERR "cannot read entity file"
    OUTPUT ${_render_out}/html_none/index.html OUTPUT_EXISTS 0)
render_cli_test("html with a label count that differs exits 2" ARGS html ${_street} ${_street}
    --labels A --out ${_render_out}/html_labels CODE 2 STDERR "--labels"
    OUTPUT ${_render_out}/html_labels/index.html OUTPUT_EXISTS 0)
render_cli_test("html with a missing point cloud exits 1 naming --cloud" ARGS html ${_street}
    --cloud ${_render_out}/none.ply --out ${_render_out}/html_nocloud CODE 1 STDERR "--cloud"
    OUTPUT ${_render_out}/html_nocloud/index.html OUTPUT_EXISTS 0)

# play: a two-frame drive to every frame's PNG, a strip and an MP4 (ffmpeg is a dependency,
# scripts/install-deps.sh), and nothing else in the folder (no staged or hidden file left).
set(_play_frame ${PROJECT_SOURCE_DIR}/tests/corpus/cases/drive_broken/keep.json)
add_test(NAME "scene-render play writes every frame, the strip and the video, nothing else"
    COMMAND bash -c "set -euo pipefail; d=${_render_out}/play; rm -rf \"$d\"; mkdir -p \"$d/drive\"; \
cp ${_play_frame} \"$d/drive/a.json\"; cp ${_play_frame} \"$d/drive/b.json\"; \
echo '{\"schema_version\": \"1.1.0\", \"id\": \"two\", \"fps\": 5, \"frames\": [{\"index\": 0, \"file\": \"a.json\"}, {\"index\": 1, \"file\": \"b.json\"}]}' > \"$d/drive/sequence.json\"; \
$<TARGET_FILE:scene-render> play \"$d/drive\" --out-dir \"$d/out\" --strip \"$d/out/strip.png\" \
    --video \"$d/out/drive.mp4\" --view bev --size 160x120; \
test \"$(ls -A \"$d/out\" | tr '\\n' ' ')\" = 'a.png b.png drive.mp4 strip.png '; \
for f in a b strip; do test \"$(head -c 4 \"$d/out/$f.png\" | od -An -tx1 | tr -d ' ')\" = 89504e47; done; \
head -c 12 \"$d/out/drive.mp4\" | grep -q ftyp")
set_tests_properties("scene-render play writes every frame, the strip and the video, nothing else"
    PROPERTIES TIMEOUT 120)
