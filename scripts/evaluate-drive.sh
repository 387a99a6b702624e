#!/usr/bin/env bash
# A drive end to end against its truth: render a moving scene with scene-render sensors
# (--frames), analyse every frame with cloud-analysis batch, track them with cloud-analysis
# track, and score the tracks with evaluate-tracks and the goal's bars (docs/evaluation.md
# "Tracking"). Prints evaluate-tracks' table; exits non-zero when a bar is missed.
# With --moving SPEED YAW_RATE the camera drives (scene-render sensors --ego-speed/--ego-yaw-rate)
# along a street scripts/make-drive-street.py writes for it (seed --seed, unless --scene), the
# batch estimates the poses (--odometry) and evaluate-odometry scores them against the truth
# first (docs/odometry.md), and the tracks are held to the moving drives' bars (MOTA and IDF1
# at least 0.9, parked cars' median speed error at most 0.3 m/s; no ID-switch bar).
# With --instances the batch takes the render's instance images too (--instances).
# usage: scripts/evaluate-drive.sh [--no-build] [--build-dir DIR] [--out DIR]
#        [--scene FILE] [--frames N] [--reuse]   (--reuse: keep a render already in --out)
#        [--moving SPEED YAW_RATE] [--seed N] [--instances]
#        [--class-config FILE]   (per-class extractor settings for the batch)
#        [--analysis "FLAGS"]    (more analysis flags for the batch, e.g. "--semantics geometry")
#        [--events]   (list every miss, false positive, ID switch and heading flip)
#        [-- extra `track` flags...]
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/common.sh"

build=1
build_dir="$STEREOSCENE_ROOT/build"
out_dir=""
scene=""
frames=100
moving=()
seed=1
reuse=0
batch_args=()
eval_args=()
track_args=()
while [ $# -gt 0 ]; do
    case "$1" in
        --no-build) build=0 ;;
        --build-dir) build_dir=$2; shift ;;
        --out) out_dir=$2; shift ;;
        --scene) scene=$2; shift ;;
        --moving) moving=("$2" "$3"); shift 2 ;;
        --seed) seed=$2; shift ;;
        --frames) frames=$2; shift ;;
        --reuse) reuse=1 ;;
        --instances) batch_args+=(--instances) ;;
        --events) eval_args+=(--events) ;;
        --class-config) batch_args+=(--class-config "$2"); shift ;;
        --analysis) read -r -a more <<<"$2"; batch_args+=("${more[@]}"); shift ;;
        --) shift; track_args=("$@"); break ;;
        -h|--help) sed -n '2,19p' "$0"; exit 0 ;;
        *) echo "evaluate-drive.sh: error: unknown argument: $1 (see --help)" >&2; exit 2 ;;
    esac
    shift
done
sensor_args=()
if [ ${#moving[@]} -gt 0 ]; then
    sensor_args=(--ego-speed "${moving[0]}" --ego-yaw-rate "${moving[1]}")
    batch_args+=(--odometry)
    [ -n "$out_dir" ] || out_dir="$build_dir/drive-moving-${moving[0]}-${moving[1]}-$seed"
else
    [ -n "$scene" ] || scene="$STEREOSCENE_ROOT/samples/drives/scenes/long-drive.json"
fi
[ -n "$out_dir" ] || out_dir="$build_dir/drive-$(basename "$scene" .json)"
mkdir -p "$out_dir"
if [ ${#moving[@]} -gt 0 ] && [ -z "$scene" ]; then
    scene="$out_dir/street.json"
    length=$(awk -v v="${moving[0]}" -v n="$frames" 'BEGIN { print v * n / 10 }')
    /usr/bin/python3 "$STEREOSCENE_ROOT/scripts/make-drive-street.py" --seed "$seed" \
        --speed "${moving[0]}" --yaw-rate "${moving[1]}" --length "$length" -o "$scene"
fi
if [ "$build" = 1 ]; then
    stereoscene_build "$build_dir" Release -- cloud-analysis scene-render
fi
ca="$build_dir/cloud_analysis/cloud-analysis"
render="$out_dir/render"

if [ "$reuse" = 0 ] || [ ! -d "$render/truth" ]; then
    rm -rf "$render"
    "$build_dir/scene_viewer/scene-render" sensors "$scene" --out "$render" --frames "$frames" \
        "${sensor_args[@]}" >&2
fi
ls "$render/image_2" | sed 's/\.png$//' >"$out_dir/frames.txt"
rm -rf "$out_dir/detections" "$out_dir/tracked"
"$ca" batch --kitti-root "$render" --list "$out_dir/frames.txt" --out-dir "$out_dir/detections" \
    --quiet "${batch_args[@]}"
if [ ${#moving[@]} -gt 0 ]; then
    "$ca" evaluate-odometry --poses "$out_dir/detections/poses.txt" --truth "$render/truth/poses.txt"
fi
"$ca" track "$out_dir/detections" --out-dir "$out_dir/tracked" --fps 10 "${track_args[@]}"
bars=(--min-mota 0.9 --min-idf1 0.9 --max-velocity-error 0.5 --max-heading-flips 0
    --max-size-spread 0.05)
if [ ${#moving[@]} -gt 0 ]; then
    bars+=(--max-still-velocity-error 0.3)
else
    bars+=(--max-id-switches 2)
fi
"$ca" evaluate-tracks --tracks "$out_dir/tracked" --truth "$render/truth" \
    --visibility "$render/visibility" --min-visible-fraction 0.25 "${bars[@]}" "${eval_args[@]}"
