#!/usr/bin/env bash
# Vehicle models the analysis was never fitted to: streets of scripts/street-seeds.sh (a parking,
# a kerbside and a pedestrian street per seed) rendered once with the project's own models and
# once with third-party CC0 vehicles from Kenney's car kit (a body for the car class, its truck
# for the truck class), each analysed with its semantic image and from the stereo pair alone and
# scored with scripts/evaluate.sh's bars (cars within 30 m at least a quarter visible;
# docs/evaluation.md "Other vehicle models"). Development set: the tuning seeds (--dev-seeds)
# with the sedan body; test set: the held-out seeds with the SUV and van bodies in turn, never
# used to choose a parameter. Prints one Markdown table. Skipped (exit 0) without the models.
# usage: scripts/evaluate-vehicle-models.sh [--no-build] [--build-dir DIR] [--out DIR]
#            [--models DIR] [--dev-seeds "2 ..."] [--held-out-seeds "13 ..."]
#            [--analysis "FLAGS"]   (more cloud-analysis flags, e.g. "--row-model partition")
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/common.sh"

build=1
build_dir="$STEREOSCENE_ROOT/build"
out_dir=""
models="$STEREOSCENE_ROOT/../shared/gltf-thirdparty"
# pedestrian_seeds (every kind of street has them), held_out_seeds, set_street_flags
source "$STEREOSCENE_ROOT/scripts/street-seeds.sh"
dev_seeds=$pedestrian_seeds
analysis_args=()
# goal, stereo_only_goal
source "$STEREOSCENE_ROOT/scripts/street-bars.sh"
while [ $# -gt 0 ]; do
    case "$1" in
        --no-build) build=0 ;;
        --build-dir) build_dir=$2; shift ;;
        --out) out_dir=$2; shift ;;
        --models) models=$2; shift ;;
        --dev-seeds) dev_seeds=$2; shift ;;
        --held-out-seeds) held_out_seeds=$2; shift ;;
        --analysis) read -r -a analysis_args <<<"$2"; shift ;;
        -h|--help) sed -n '2,12p' "$0"; exit 0 ;;
        *)
            echo "evaluate-vehicle-models.sh: error: unknown argument: $1 (see --help)" >&2
            exit 2
            ;;
    esac
    shift
done
kit="$models/kenney-car-kit"
dev_bodies=(sedan)
test_bodies=(suv van)
for body in "${dev_bodies[@]}" "${test_bodies[@]}" truck; do
    if [ ! -f "$kit/$body.glb" ]; then
        echo "evaluate-vehicle-models.sh: no $kit/$body.glb; skipped" >&2
        exit 0
    fi
done
if [ "$build" = 1 ]; then
    stereoscene_build "$build_dir" Release -- cloud-analysis scene-render
fi
ca="$build_dir/cloud_analysis/cloud-analysis"
sr="$build_dir/scene_viewer/scene-render"
[ -n "$out_dir" ] || out_dir="$build_dir/evaluation-vehicle-models"
mkdir -p "$out_dir"

# One class table per body: the shipped table with the car and truck models swapped (absolute
# paths, so the table may live in the output folder).
for body in "${dev_bodies[@]}" "${test_bodies[@]}"; do
    python3 -c 'import sys; sys.path.insert(0, sys.argv[1]); import stereoscene_assets as a; a.write_body_table(*sys.argv[2:])' \
        "$STEREOSCENE_ROOT/scripts" "$kit" "$body" "$out_dir/classes-$body.json"
done

rows=()
score() {  # set drawn-with name dir scene
    local set=$1 drawn=$2 name=$3 dir=$4 scene=$5
    for path in labels stereo-only; do
        local base="$dir-$path" flags=() bars=("${goal[@]}")
        if [ "$path" = stereo-only ]; then
            flags=(--semantics geometry)
            bars=("${stereo_only_goal[@]}")
        fi
        "$ca" --kitti-root "$dir" --frame 000000 "${flags[@]}" "${analysis_args[@]}" \
            -o "$base.json" 2>"$base.log"
        local code=0
        "$ca" evaluate --entities "$base.json" --reference "$scene" "${bars[@]}" \
            --min-visible-fraction 0.25 --kitti-root "$dir" --frame 000000 \
            --json "$base-eval.json" >"$base-eval.txt" 2>&1 || code=$?
        [ "$code" = 0 ] || [ "$code" = 3 ] || { cat "$base-eval.txt" >&2; exit 1; }
        rows+=("$set=$drawn=$path=$name=$base-eval.json")
    done
}
streets() {  # set "seeds" bodies...: every street of the seeds, the bodies in turn
    local set=$1 seeds=$2
    shift 2
    local street_bodies=("$@") n=0
    for seed in $seeds; do
        for kind in parking kerbside pedestrians; do
            local name="$kind-$seed" scene="$out_dir/$kind-$seed.json"
            set_street_flags "$kind"
            python3 "$STEREOSCENE_ROOT/scripts/make-parking-scene.py" --seed "$seed" \
                "${street_flags[@]}" -o "$scene"
            local body=${street_bodies[$((n % ${#street_bodies[@]}))]}
            n=$((n + 1))
            local drawn
            for drawn in own "$body"; do
                local classes=()
                [ "$drawn" = own ] || classes=(--classes "$out_dir/classes-$body.json")
                "$sr" sensors "$scene" --out "$out_dir/$drawn/$name" --frame 000000 \
                    --seed "$seed" --label-bleed 3 "${classes[@]}" >/dev/null
                score "$set" "$drawn" "$name" "$out_dir/$drawn/$name" "$scene"
            done
        done
    done
}
streets development "$dev_seeds" "${dev_bodies[@]}"
streets test "$held_out_seeds" "${test_bodies[@]}"

python3 - "${rows[@]}" <<'EOF'
import json, statistics, sys
rows = {}
for arg in sys.argv[1:]:
    street_set, models, path, name, file = arg.split("=", 4)
    models = "the project's own" if models == "own" else "Kenney " + models
    d = json.load(open(file))
    e = d["entities"]
    bins = e["classes"].get("car", {}).get("bins", {})
    near = [bins.get(b, {}) for b in ("0-10", "10-20", "20-30")]
    r = rows.setdefault((street_set, path, models),
                        {"streets": 0, "met": 0, "ref": 0, "hit": 0, "spur": 0, "centre": []})
    r["streets"] += 1
    r["met"] += int(d["bars"]["pass"])
    r["ref"] += sum(b.get("reference", 0) for b in near)
    r["hit"] += sum(b.get("matched", 0) for b in near)
    r["spur"] += sum(b.get("spurious", 0) for b in near)
    r["centre"] += [m["centre_error_m"] for m in e["matches"]
                    if m["class"] == "car" and m["range_m"] < 30.0]
print("| set | classes from | vehicle models | streets | cars found | recall | spurious cars "
      "| precision | median centre error, m | streets meeting the bars |")
print("|---|---|---|---|---|---|---|---|---|---|")
for (street_set, path, models), r in rows.items():
    c = r["centre"]
    centre = f"{statistics.median(c):.2f}" if c else "-"
    print(f"| {street_set} | {'semantic image' if path == 'labels' else 'stereo pair only'} "
          f"| {models} | {r['streets']} | {r['hit']}/{r['ref']} "
          f"| {r['hit'] / max(r['ref'], 1):.3f} | {r['spur']} "
          f"| {r['hit'] / max(r['hit'] + r['spur'], 1):.3f} | {centre} "
          f"| {r['met']}/{r['streets']} |")
EOF
