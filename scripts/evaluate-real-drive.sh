#!/usr/bin/env bash
# Scores cloud-analysis on the real KITTI drive (../shared/data/kitti_odometry_02, 20 frames)
# against the project's hand-drawn 2D boxes (samples/labels-2d/kitti_odometry_02.json): the
# stereo pair alone through `batch`, every entity's 3D box projected into the left image and
# matched to the boxes (docs/evaluation.md "Real drive"). Prints the table of
# `evaluate --labels-2d` and writes its JSON; then the same frames tracked over the ground
# (the batch's poses, `track` with its defaults) scored on their confirmed tracks alone
# (`evaluate --tracked-only`).
# usage: scripts/evaluate-real-drive.sh [--no-build] [--build-dir DIR] [--drive DIR] [--out DIR]
#            [-- extra batch flags]
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/common.sh"

build=1
build_dir="$STEREOSCENE_ROOT/build"
drive="$STEREOSCENE_ROOT/../shared/data/kitti_odometry_02"
out_dir=""
extra=()
while [ $# -gt 0 ]; do
    case "$1" in
        --no-build) build=0 ;;
        --build-dir) build_dir=$2; shift ;;
        --drive) drive=$2; shift ;;
        --out) out_dir=$2; shift ;;
        --) shift; extra=("$@"); break ;;
        -h|--help) sed -n '2,8p' "$0"; exit 0 ;;
        *) echo "evaluate-real-drive.sh: unknown argument $1" >&2; exit 2 ;;
    esac
    shift
done
if [ ! -d "$drive/image_2" ] || [ ! -d "$drive/image_3" ]; then
    echo "evaluate-real-drive.sh: no real drive at $drive (needs image_2 image_3 calib.txt); skipped" >&2
    exit 0
fi
if [ "$build" = 1 ]; then
    stereoscene_build "$build_dir" Release -- cloud-analysis
fi
ca="$build_dir/cloud_analysis/cloud-analysis"
[ -n "$out_dir" ] || out_dir="$build_dir/evaluation/real-drive"
mkdir -p "$out_dir/entities"
for left in "$drive"/image_2/*.png; do
    echo "$left $drive/image_3/$(basename "$left")"
done > "$out_dir/pairs.txt"
echo "=== real drive $(basename "$drive"), stereo pair only, against the hand-drawn 2D boxes ==="
labels="$STEREOSCENE_ROOT/samples/labels-2d/kitti_odometry_02.json"
"$ca" batch --pairs "$out_dir/pairs.txt" --calib "$drive/calib.txt" \
    --out-dir "$out_dir/entities" -q --odometry "${extra[@]}"
"$ca" evaluate --labels-2d "$labels" --entities "$out_dir/entities" \
    --json "$out_dir/labels-2d-eval.json"
echo "=== the same frames tracked over the ground, confirmed tracks only ==="
rm -rf "$out_dir/tracked"
mkdir -p "$out_dir/tracked"
"$ca" track "$out_dir/entities" --out-dir "$out_dir/tracked" --quiet
"$ca" evaluate --labels-2d "$labels" --entities "$out_dir/tracked" --tracked-only \
    --json "$out_dir/labels-2d-tracked-eval.json"
