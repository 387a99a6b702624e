#!/usr/bin/env bash
# The closed loop, side by side for the extractors: for every rendered sample
# (<samples>/<scene>/ in KITTI layout, truth <samples>/<scene>/scene.json or
# <samples>/scenes/<scene>.json) run cloud-analysis with the default settings and
# --method instances|centroid|variance, with the instance image as input (--instances, the
# row "with-instances": median centre error bar 0.3 m) and the stereo-only path (--semantics
# geometry, the semantic image ignored; its own CI bars are in docs/stereo-only.md), score each
# against the truth with `evaluate` and the bars of docs/evaluation.md "Closed loop", and print
# one Markdown table.
# usage: scripts/closed-loop.sh [--no-build] [--build-dir DIR] [--samples DIR] [--out DIR]
#        [--render]   (--render: first render <samples>/scenes/*.json with scene-render sensors
#                      into --out, e.g. for scenes without committed renders)
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/common.sh"

build=1
build_dir="$STEREOSCENE_ROOT/build"
samples="$STEREOSCENE_ROOT/samples/rendered"
out_dir=""
render=0
while [ $# -gt 0 ]; do
    case "$1" in
        --no-build) build=0 ;;
        --build-dir) build_dir=$2; shift ;;
        --samples) samples=$2; shift ;;
        --out) out_dir=$2; shift ;;
        --render) render=1 ;;
        -h|--help) sed -n '2,9p' "$0"; exit 0 ;;
        *) echo "closed-loop.sh: error: usage: unknown argument: $1 (see --help)" >&2; exit 2 ;;
    esac
    shift
done
[ -n "$out_dir" ] || out_dir="$build_dir/closed-loop"
mkdir -p "$out_dir"
targets=(cloud-analysis)
[ "$render" = 1 ] && targets+=(scene-render)
if [ "$build" = 1 ]; then
    stereoscene_build "$build_dir" Release -- "${targets[@]}"
fi
ca="$build_dir/cloud_analysis/cloud-analysis"

if [ "$render" = 1 ]; then
    for scene in "$samples"/scenes/*.json; do
        name=$(basename "$scene" .json)
        extra=()
        [ -f "${scene%.json}.sensors" ] && read -r -a extra <"${scene%.json}.sensors"
        "$build_dir/scene_viewer/scene-render" sensors "$scene" --out "$out_dir/rendered/$name" \
            "${extra[@]}" >&2
        cp "$scene" "$out_dir/rendered/$name/scene.json"
    done
    samples="$out_dir/rendered"
fi

bars=(--bar-class car --bar-range 30 --require-recall 1.0 --max-spurious 0
      --max-stuff-on-things 0 --max-median-heading-error 10
      --min-good-iou-fraction 0.7)
# References less than a quarter visible are not scored (KITTI's moderate setting); the table
# also shows every car, hidden ones included ("all cars" columns).
visibility=(--min-visible-fraction 0.25)
evals=()
for calib in "$samples"/*/calib/calib_cam_to_cam.txt; do
    [ -f "$calib" ] || continue
    dir=$(dirname "$(dirname "$calib")")
    name=$(basename "$dir")
    truth="$dir/scene.json"
    [ -f "$truth" ] || truth="$samples/scenes/$name.json"
    [ -f "$truth" ] || { echo "closed-loop.sh: $dir has no scene file; skipped" >&2; continue; }
    for image in "$dir"/image_2/*.png; do
        frame=$(basename "$image" .png)
        for method in instances with-instances centroid variance stereo-only; do
            base="$out_dir/$name-$frame-$method"
            flags=(--method "$method")
            method_bars=(--max-median-centre-error 0.5)
            [ "$method" = stereo-only ] && flags=(--semantics geometry)
            if [ "$method" = with-instances ]; then
                flags=(--instances)
                method_bars=(--max-median-centre-error 0.3)
            fi
            "$ca" --kitti-root "$dir" --frame "$frame" "${flags[@]}" -o "$base.json" \
                2>"$base.log"
            code=0
            "$ca" evaluate --entities "$base.json" --reference "$truth" "${bars[@]}" \
                "${method_bars[@]}" "${visibility[@]}" --visibility "$dir/visibility/$frame.json" \
                --json "$base-eval.json" >"$base-eval.txt" 2>&1 || code=$?
            [ "$code" = 0 ] || [ "$code" = 3 ] || { cat "$base-eval.txt" >&2; exit 1; }
            evals+=("$name/$frame=$method=$base-eval.json")
        done
    done
done
[ ${#evals[@]} -gt 0 ] || { echo "closed-loop.sh: no rendered samples under $samples" >&2; exit 1; }

python3 - "${evals[@]}" <<'EOF'
import json, statistics, sys
print("| scene | extractor | cars <= 30 m (all) | found (all) | spurious cars | stuff on things "
      "| median centre error m | median heading error deg | BEV IoU >= 0.5 (all) | bars |")
print("|---|---|---|---|---|---|---|---|---|---|")
for arg in sys.argv[1:]:
    scene, method, path = arg.split("=", 2)
    d = json.load(open(path))
    e = d["entities"]
    bins = e["classes"].get("car", {}).get("bins", {})
    near = [bins.get(b, {}) for b in ("0-10", "10-20", "20-30")]
    ref = sum(b.get("reference", 0) for b in near)
    hit = sum(b.get("matched", 0) for b in near)
    spur = sum(b.get("spurious", 0) for b in near)
    good = sum(b.get("good_iou", 0) for b in near)
    cars = [m for m in e["matches"] if m["class"] == "car" and m["range_m"] < 30.0]
    centre = statistics.median([m["centre_error_m"] for m in cars]) if cars else float("nan")
    head = statistics.median([m["heading_error_deg"] for m in cars]) if cars else float("nan")
    stuff = sum(c["bins"][b]["spurious"] for c in e["classes"].values() if not c["thing"]
                for b in ("0-10", "10-20", "20-30"))
    verdict = "pass" if d["bars"]["pass"] else "FAIL"
    centre = f"{centre:.2f}" if cars else "-"
    head = f"{head:.1f}" if cars else "-"
    u = e["unfiltered"]
    print(f"| {scene} | {method} | {ref} ({u['reference']}) | {hit} ({u['matched']}) | {spur} | "
          f"{stuff} | {centre} | {head} | {good}/{ref} ({u['good_iou']}/{u['reference']}) | "
          f"{verdict} |")
EOF
