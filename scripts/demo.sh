#!/usr/bin/env bash
# Installs what is missing, builds (Release), runs cloud-analysis on the bundled samples and
# scene-render on its output and on the crafted baseline, writes the interactive viewer and
# OUTPUT_DIR/index.html (the viewer embedded and every output linked), then prints that page
# first and where each output is.
# usage: scripts/demo.sh [OUTPUT_DIR]      (default: out/demo)
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/common.sh"

out=${1:-"$STEREOSCENE_ROOT/out/demo"}
build="$STEREOSCENE_ROOT/build"
echo "Demo page (written when the demo ends): $out/index.html" >&2
stereoscene_build "$build" Release -- cloud-analysis scene-render

analyse="$build/cloud_analysis/cloud-analysis"
render="$build/scene_viewer/scene-render"
samples="$STEREOSCENE_ROOT/samples"
mkdir -p "$out"
outputs=()
listing=()
note() {
    outputs+=("$(printf '%-34s %s' "$1" "$2")")
    listing+=("$1"$'\t'"$2")
}

# 1. cloud-analysis on the rendered street (samples/rendered: made by scene-render sensors from
#    a known scene): clouds in three formats, disparity, entities by the default extractor and by
#    the thesis's one-entity-per-class extractors.
r="$samples/rendered"
street=(--kitti-root "$r/street" --frame 000000)
echo "== cloud-analysis: rendered street (instances)" >&2
"$analyse" "${street[@]}" -o "$out/street-instances.json" \
    --xyz "$out/street.xyz" --pcd "$out/street.pcd" --ply "$out/street.ply" \
    --disparity-png "$out/street-disparity.png" --timings
note "entities (instances)" "$out/street-instances.json"
note "cloud for CloudCompare" "$out/street.xyz"
note "cloud for PCL" "$out/street.pcd"
note "cloud for MeshLab/CloudCompare" "$out/street.ply"
note "disparity (8-bit)" "$out/street-disparity.png"
for method in centroid variance; do
    echo "== cloud-analysis: rendered street (thesis extractor: $method)" >&2
    "$analyse" "${street[@]}" --method "$method" -o "$out/street-$method.json"
    note "entities ($method, thesis)" "$out/street-$method.json"
done

# 2. The closed loop on every rendered scene: analyse, then score against the scene's truth.
for scene in thesis-one-car street parking-row; do
    [ "$scene" = street ] || "$analyse" --kitti-root "$r/$scene" --frame 000000 \
        -o "$out/$scene-instances.json"
    echo "== evaluate: $scene against its truth" >&2
    "$analyse" evaluate --entities "$out/$scene-instances.json" \
        --reference "$r/scenes/$scene.json" --json "$out/$scene-eval.json" >&2
    note "scores, $scene" "$out/$scene-eval.json"
done

# 3. scene-render: the crafted baseline and the analysis in camera, chase and BEV views.
for view in camera chase bev; do
    "$render" "$samples/baselines/street.json" --view "$view" -o "$out/baseline-$view.png"
    note "baseline, $view view" "$out/baseline-$view.png"
    "$render" "$out/street-instances.json" --view "$view" -o "$out/street-$view.png"
    note "street analysis, $view view" "$out/street-$view.png"
done
"$render" "$out/street-instances.json" --view camera --background "$r/street/image_2/000000.png" \
    -o "$out/street-camera-over-left.png"
note "analysis over the left image" "$out/street-camera-over-left.png"
"$render" "$out/street-instances.json" --view chase --cloud "$out/street.ply" \
    -o "$out/street-chase-cloud.png"
note "analysis + point cloud, chase" "$out/street-chase-cloud.png"
"$render" grid --inputs "$r/scenes/street.json" "$out/street-centroid.json" \
    "$out/street-variance.json" "$out/street-instances.json" \
    --labels "truth" "centre of mass" "variance" "instances" --view bev \
    -o "$out/street-comparison.png"
note "comparison grid (BEV)" "$out/street-comparison.png"
"$render" "$samples/baselines/street.json" --view chase --export-glb "$out/baseline.glb" \
    -o "$out/baseline-chase.png"
note "baseline scene as glTF" "$out/baseline.glb"

# The same street from the stereo pair alone (no semantic image): ground, obstacles and classes
# from geometry (docs/stereo-only.md), scored against the truth like the labelled run.
echo "== cloud-analysis: rendered street, stereo pair only" >&2
"$analyse" --left "$r/street/image_2/000000.png" --right "$r/street/image_3/000000.png" \
    --calib "$r/street/calib/calib_cam_to_cam.txt" --frame 000000 --semantics geometry \
    -o "$out/street-stereo-only.json" --semantic-out "$out/street-stereo-only-classes.png"
"$analyse" evaluate --entities "$out/street-stereo-only.json" \
    --reference "$r/scenes/street.json" --json "$out/street-stereo-only-eval.json" >&2
"$render" "$out/street-stereo-only.json" --view camera \
    --background "$r/street/image_2/000000.png" -o "$out/street-stereo-only-camera.png"
note "entities, stereo pair only" "$out/street-stereo-only.json"
note "classes from geometry" "$out/street-stereo-only-classes.png"
note "scores, stereo pair only" "$out/street-stereo-only-eval.json"
note "stereo-only over the left image" "$out/street-stereo-only-camera.png"
for view in camera bev; do
    "$render" grid --inputs "$r/scenes/street.json" "$out/street-instances.json" \
        "$out/street-stereo-only.json" --labels "truth" "with the semantic image" \
        "stereo pair only" --columns 1 --view "$view" -o "$out/street-labels-vs-stereo-$view.png"
    note "semantic image vs stereo pair only, $view view" "$out/street-labels-vs-stereo-$view.png"
done

# 3b. A drive: the short sample drive rendered with its truth (half size, 10 frames, to keep the
#     demo fast), analysed, tracked, scored, then played to a video and a BEV strip with trails.
echo "== drive: scene-render sensors --frames, batch, track, evaluate-tracks, play" >&2
drive="$out/drive"
rm -rf "$drive"
"$render" sensors "$samples/drives/scenes/crossing.json" --out "$drive/sensors" --frames 10 \
    --fps 10 --size 621x188
ls "$drive/sensors/image_2" | sed 's/\.png$//' > "$drive/frames.txt"
mkdir -p "$drive/analysed"
"$analyse" batch --kitti-root "$drive/sensors" --list "$drive/frames.txt" \
    --out-dir "$drive/analysed" --quiet
"$analyse" track "$drive/analysed" --out-dir "$drive/tracked" --fps 10
"$analyse" evaluate-tracks --tracks "$drive/tracked" --truth "$drive/sensors/truth" \
    --visibility "$drive/sensors/visibility" --min-visible-fraction 0.25 > "$drive/tracking.txt"
note "drive: tracking scores" "$drive/tracking.txt"
if "$render" html "$drive/tracked" --backgrounds "$drive/sensors/image_2" --title "sample drive" \
    --out "$drive/viewer"; then
    note "drive: interactive viewer (timeline)" "$drive/viewer/index.html"
fi
video=()
command -v ffmpeg >/dev/null && video=(--video "$drive/drive-camera.mp4")
"$render" play "$drive/tracked" --out-dir "$drive/camera" --view camera --size 621x188 \
    --backgrounds "$drive/sensors/image_2" "${video[@]}"
[ ${#video[@]} -gt 0 ] && note "drive: camera view over the left images (MP4)" "$drive/drive-camera.mp4"
"$render" play "$drive/tracked" --out-dir "$drive/bev" --view bev --size 320x320 --trail 10 \
    --strip "$drive/drive-bev-strip.png" --strip-frames 4
note "drive: BEV strip with track trails" "$drive/drive-bev-strip.png"

# 3c. A moving camera: a street made for a drive, rendered while the car drives 8 m/s turning
#     4 degrees a second (half size, 20 frames), analysed with odometry and tracking in one
#     batch, its poses scored against the truth, then played in the drive's world: a BEV with
#     the car's path and the tracks over the ground.
echo "== moving drive: sensors --ego-speed, batch --odometry --track, evaluate-odometry, play" >&2
moving="$out/moving-drive"
rm -rf "$moving"
mkdir -p "$moving"
/usr/bin/python3 "$STEREOSCENE_ROOT/scripts/make-drive-street.py" --seed 3 --speed 8 \
    --yaw-rate 4 --length 16 -o "$moving/street.json"
"$render" sensors "$moving/street.json" --out "$moving/sensors" --frames 20 --fps 10 \
    --ego-speed 8 --ego-yaw-rate 4 --size 621x188
ls "$moving/sensors/image_2" | sed 's/\.png$//' > "$moving/frames.txt"
"$analyse" batch --kitti-root "$moving/sensors" --list "$moving/frames.txt" \
    --out-dir "$moving/analysed" --odometry --track --quiet
"$analyse" evaluate-odometry --poses "$moving/analysed/poses.txt" \
    --truth "$moving/sensors/truth/poses.txt" > "$moving/odometry.txt"
note "moving drive: odometry scores" "$moving/odometry.txt"
"$render" play "$moving/analysed" --out-dir "$moving/bev" --view bev --size 320x320 --trail 20 \
    --strip "$moving/drive-bev-strip.png" --strip-frames 4
note "moving drive: BEV strip, path and tracks in the world" "$moving/drive-bev-strip.png"

# 4. A real KITTI frame, when the shared data is beside the project (never bundled).
kitti="$STEREOSCENE_ROOT/../shared/data/kitti15"
if [ -d "$kitti/image_2" ]; then
    echo "== cloud-analysis: KITTI 2015 frame 000000_10 (from ../shared/data)" >&2
    "$analyse" --kitti-root "$kitti" --frame 000000_10 -o "$out/kitti-000000_10.json" \
        --ply "$out/kitti-000000_10.ply" --timings
    "$render" "$out/kitti-000000_10.json" --view camera \
        --background "$kitti/image_2/000000_10.png" -o "$out/kitti-000000_10-camera.png"
    "$render" "$out/kitti-000000_10.json" --view bev -o "$out/kitti-000000_10-bev.png"
    note "KITTI entities" "$out/kitti-000000_10.json"
    note "KITTI camera view over the image" "$out/kitti-000000_10-camera.png"
    note "KITTI BEV" "$out/kitti-000000_10-bev.png"
fi

# 5. The interactive viewer: the analysis with its cloud and left image, compared with the truth,
#    the stereo-only run and the thesis extractors; then the page that embeds it and links
#    everything above.
if "$render" html "$out/street-instances.json" "$r/scenes/street.json" \
    "$out/street-stereo-only.json" "$out/street-centroid.json" "$out/street-variance.json" \
    --labels instances truth "stereo only" "centre of mass" variance --cloud "$out/street.ply" \
    --background "$r/street/image_2/000000.png" --title "rendered street" --out "$out/viewer"; then
    note "interactive viewer (browser)" "$out/viewer/index.html"
else
    echo "demo: the viewer was not written (scripts/install-deps.sh installs three.js)" >&2
fi
printf '%s\n' "${listing[@]}" > "$out/.index-list.tsv"
/usr/bin/python3 "$STEREOSCENE_ROOT/scripts/demo_index.py" "$out" "$out/.index-list.tsv"
rm -f "$out/.index-list.tsv"

echo "Demo page (open in a browser): $out/index.html"
echo
echo "Demo outputs:"
printf '  %s\n' "${outputs[@]}"
