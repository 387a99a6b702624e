#!/usr/bin/env bash
# The closed loop through several stereo rigs: every scene of <samples>/scenes/*.json rendered
# by scene-render sensors with each rig preset (kitti, cityscapes, argoverse, zed, realsense),
# analysed by cloud-analysis with the default settings (fitted to the rig: docs/cli.md "Any
# stereo rig") with its semantic image and with the stereo pair alone, and scored with the
# closed loop's bars (labelled path) and the stereo-only bars, over the rig's useful range:
# 30 m x sqrt(fx B / KITTI's fx B), at most 30 m, the depth at which the rig's depth error is
# KITTI's at 30 m, scored over the evaluator's 10 m bins within it (at least the first).
# Prints one Markdown table.
# usage: scripts/rig-loop.sh [--no-build] [--build-dir DIR] [--samples DIR] [--out DIR]
#        [--rigs "kitti zed ..."] [--paths "labels stereo-only"] [--analysis "FLAGS"]
#   --analysis: more flags for every analysis (e.g. "--row-model partition", to compare settings)
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/common.sh"

build=1
build_dir="$STEREOSCENE_ROOT/build"
samples="$STEREOSCENE_ROOT/samples/rendered"
out_dir=""
rigs="kitti cityscapes argoverse zed realsense"
paths="labels stereo-only"
analysis=""
while [ $# -gt 0 ]; do
    case "$1" in
        --no-build) build=0 ;;
        --build-dir) build_dir=$2; shift ;;
        --samples) samples=$2; shift ;;
        --out) out_dir=$2; shift ;;
        --rigs) rigs=$2; shift ;;
        --paths) paths=$2; shift ;;
        --analysis) analysis=$2; shift ;;
        -h|--help) sed -n '2,11p' "$0"; exit 0 ;;
        *) echo "rig-loop.sh: error: usage: unknown argument: $1 (see --help)" >&2; exit 2 ;;
    esac
    shift
done
[ -n "$out_dir" ] || out_dir="$build_dir/rig-loop"
mkdir -p "$out_dir"
[ "$build" = 1 ] && stereoscene_build "$build_dir" Release -- cloud-analysis scene-render
ca="$build_dir/cloud_analysis/cloud-analysis"
sr="$build_dir/scene_viewer/scene-render"

labels_bars=(--bar-class car --require-recall 1.0 --max-spurious 0
             --max-stuff-on-things 0 --max-median-centre-error 0.5
             --max-median-heading-error 10 --min-good-iou-fraction 0.7)
stereo_bars=(--bar-class car --require-recall 1.0 --max-median-centre-error 0.5
             --max-median-heading-error 10 --max-spurious 1)
rows=()
for rig in $rigs; do
    for scene in "$samples"/scenes/*.json; do
        name=$(basename "$scene" .json)
        dir="$out_dir/$rig/$name"
        extra=()
        [ -f "${scene%.json}.sensors" ] && read -r -a extra <"${scene%.json}.sensors"
        "$sr" sensors "$scene" --out "$dir" --frame 000000 --seed 0 --preset "$rig" "${extra[@]}"
        # The rig's useful range from its calibration (P_rect_03's -fx B).
        range=$(awk '/^P_rect_03:/ { fb = -$5 } END {
            r = 30 * sqrt(fb / (721.5377 * 0.54)); printf "%.1f", (r > 30 ? 30 : r) }' \
            "$dir/calib/calib_cam_to_cam.txt")
        bar_range=$(awk -v r="$range" 'BEGIN { b = int(r / 10) * 10; print (b < 10 ? 10 : b) }')
        for path in $paths; do
            base="$out_dir/$rig-$name-$path"
            flags=()
            # shellcheck disable=SC2206 # the extra flags are split on purpose
            [ -n "$analysis" ] && flags=($analysis)
            bars=("${labels_bars[@]}")
            if [ "$path" = stereo-only ]; then
                flags+=(--semantics geometry)
                bars=("${stereo_bars[@]}")
            fi
            start=$(date +%s.%N)
            "$ca" --kitti-root "$dir" --frame 000000 "${flags[@]}" -o "$base.json" 2>"$base.log"
            seconds=$(echo "$(date +%s.%N) - $start" | bc)
            code=0
            "$ca" evaluate --entities "$base.json" --reference "$scene" "${bars[@]}" \
                --bar-range "$bar_range" --min-visible-fraction 0.25 --kitti-root "$dir" \
                --frame 000000 --json "$base-eval.json" >"$base-eval.txt" 2>&1 || code=$?
            [ "$code" = 0 ] || [ "$code" = 3 ] || { cat "$base-eval.txt" >&2; exit 1; }
            rows+=("$rig=$name=$path=$bar_range=$seconds=$base.json=$base-eval.json")
        done
    done
done

python3 - "${rows[@]}" <<'EOF'
import json, statistics, sys
print("| rig | fx px | baseline m | range m | scene | path | cars | found | spurious | "
      "median centre error m | BEV IoU >= 0.5 | wall s | bars |")
print("|---|---|---|---|---|---|---|---|---|---|---|---|---|")
for arg in sys.argv[1:]:
    rig, scene, path, rng, seconds, entities, evaluation = arg.split("=", 6)
    cam = json.load(open(entities))["frame"]["camera"]
    d = json.load(open(evaluation))
    e = d["entities"]
    bins = e["classes"].get("car", {}).get("bins", {})
    near = [bins.get(b, {}) for b in ("0-10", "10-20", "20-30")[: int(rng) // 10]]
    ref = sum(b.get("reference", 0) for b in near)
    hit = sum(b.get("matched", 0) for b in near)
    spur = sum(b.get("spurious", 0) for b in near)
    good = sum(b.get("good_iou", 0) for b in near)
    cars = [m for m in e["matches"] if m["class"] == "car" and m["range_m"] < int(rng)]
    centre = f"{statistics.median([m['centre_error_m'] for m in cars]):.2f}" if cars else "-"
    verdict = "pass" if d["bars"]["pass"] else "FAIL"
    print(f"| {rig} | {cam['fx']:.0f} | {cam['baseline_m']:.3f} | {rng} | {scene} | {path} | "
          f"{ref} | {hit} | {spur} | {centre} | {good}/{ref} | {float(seconds):.2f} | {verdict} |")
EOF
