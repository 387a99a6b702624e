#!/usr/bin/env bash
# The odometry loop: a street made for a drive with a moving camera
# (scripts/make-drive-street.py), rendered by scene-render sensors --frames with the same speed
# and yaw rate (truth/poses.txt), analysed by cloud-analysis batch --odometry, its poses scored
# by evaluate-odometry with the bars given after the frame count; then tracked over the ground
# and scored; then the moving camera's bad flags.
# usage: odometry_loop.sh SCENE_RENDER CLOUD_ANALYSIS PYTHON SPEED YAW_RATE FRAMES [bars...]
set -euo pipefail
render=$1 analyse=$2 python=$3 speed=$4 yaw=$5 frames=$6
shift 6
root=$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)
d=$(mktemp -d)
trap 'rm -rf "$d"' EXIT

"$python" "$root/scripts/make-drive-street.py" --seed 3 --speed "$speed" --yaw-rate "$yaw" \
    --length "$(awk -v v="$speed" -v n="$frames" 'BEGIN { print v * n / 10 }')" -o "$d/street.json"
"$render" sensors "$d/street.json" --out "$d/drive" --frames "$frames" --fps 10 \
    --ego-speed "$speed" --ego-yaw-rate "$yaw"
test "$(wc -l < "$d/drive/truth/poses.txt")" = "$frames"
grep -q '"pose"' "$d/drive/truth/0000000001.json"
ls "$d/drive/image_2" | sed 's/\.png$//' > "$d/frames.txt"
# One batch for both checks: the instance images give the tracker its cars and leave the class
# image, and so the odometry's vote mask and poses, as they are without them.
"$analyse" batch --kitti-root "$d/drive" --list "$d/frames.txt" --out-dir "$d/analysed" \
    --odometry --instances --quiet --report "$d/report.json"
"$analyse" evaluate-odometry --poses "$d/analysed/poses.txt" --truth "$d/drive/truth/poses.txt" \
    "$@"
# Tracked over the ground: parked cars stand still and keep their tracks (MOTA 0.91-0.95 on these
# 30-frame drives: a margin below, as the first frames see the far rows only;
# scripts/evaluate-drive.sh holds 100-frame drives to 0.9).
"$analyse" track "$d/analysed" --out-dir "$d/tracked" --quiet
"$analyse" evaluate-tracks --tracks "$d/tracked" --truth "$d/drive/truth" \
    --visibility "$d/drive/visibility" --min-visible-fraction 0.25 --min-mota 0.85 \
    --min-idf1 0.9 --max-still-velocity-error 0.3 --max-heading-flips 0 --max-size-spread 0.05
# The rig's disparity offset is estimated and reported; --no-disparity-offset leaves it out,
# and without --odometry it is refused (exit 2, nothing written).
grep -q '"disparity_offset_px"' "$d/report.json"
head -3 "$d/frames.txt" > "$d/three.txt"
"$analyse" batch --kitti-root "$d/drive" --list "$d/three.txt" --out-dir "$d/fixed" \
    --odometry --no-disparity-offset --quiet --report "$d/fixed.json"
test "$(wc -l < "$d/fixed/poses.txt")" = 3
if grep -q '"disparity_offset_px"' "$d/fixed.json"; then exit 1; fi
set +e
"$analyse" batch --kitti-root "$d/drive" --list "$d/three.txt" --out-dir "$d/refused" \
    --no-disparity-offset 2> "$d/err"
code=$?
set -e
test "$code" = 2 && grep -q -- "--no-disparity-offset" "$d/err" && test ! -e "$d/refused"

# A moving camera needs a drive, and a sane speed.
set +e
"$render" sensors "$d/street.json" --out "$d/one" --ego-speed 5 2> "$d/err"
code=$?
set -e
test "$code" = 2 && grep -q -- "--ego-speed" "$d/err" && test ! -e "$d/one"
set +e
"$render" sensors "$d/street.json" --out "$d/fast" --frames 2 --ego-speed 500 2> "$d/err"
code=$?
set -e
test "$code" = 2 && grep -q -- "--ego-speed must be within" "$d/err"
echo "odometry loop: $frames frames at $speed m/s turning $yaw deg/s, bad flags refused"
