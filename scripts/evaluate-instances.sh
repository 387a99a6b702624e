#!/usr/bin/env bash
# The instance-image input against the labelled path it replaces: every rendered street of
# scripts/street-seeds.sh (parking, kerbside and pedestrian streets; tuning seeds, then the
# held-out ones apart) analysed with and without --instances and scored against its truth
# (cars within 30 m at least a quarter visible), then the KITTI frames of ../shared/data/kitti15
# with their instance images (docs/evaluation.md "With instance images").
# usage: scripts/evaluate-instances.sh [--no-build] [--build-dir DIR] [--out DIR]
#            [--seeds "2 3 ..."] [--held-out-seeds "13 ..."] [--kitti-root DIR]
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/common.sh"

build=1
build_dir="$STEREOSCENE_ROOT/build"
out_dir=""
kitti_root="$STEREOSCENE_ROOT/../shared/data/kitti15"
# pedestrian_seeds, held_out_seeds (parking_seeds and kerbside_seeds are wider), set_street_flags
source "$STEREOSCENE_ROOT/scripts/street-seeds.sh"
seeds=$pedestrian_seeds
while [ $# -gt 0 ]; do
    case "$1" in
        --no-build) build=0 ;;
        --build-dir) build_dir=$2; shift ;;
        --out) out_dir=$2; shift ;;
        --seeds) seeds=$2; shift ;;
        --held-out-seeds) held_out_seeds=$2; shift ;;
        --kitti-root) kitti_root=$2; shift ;;
        -h|--help) sed -n '2,8p' "$0"; exit 0 ;;
        *) echo "evaluate-instances.sh: error: unknown argument: $1 (see --help)" >&2; exit 2 ;;
    esac
    shift
done
if [ "$build" = 1 ]; then
    stereoscene_build "$build_dir" Release -- cloud-analysis scene-render
fi
ca="$build_dir/cloud_analysis/cloud-analysis"
[ -n "$out_dir" ] || out_dir="$build_dir/evaluation-instances"
mkdir -p "$out_dir"

evals=()
score_street() {  # set kind seed
    local set=$1 kind=$2 seed=$3
    set_street_flags "$kind"
    local name="$kind-$seed" scene="$out_dir/$kind-$seed.json" dir="$out_dir/$kind-$seed"
    python3 "$STEREOSCENE_ROOT/scripts/make-parking-scene.py" --seed "$seed" \
        "${street_flags[@]}" -o "$scene"
    "$build_dir/scene_viewer/scene-render" sensors "$scene" --out "$dir" --frame 000000 \
        --seed "$seed" --label-bleed 3 >/dev/null
    for path in labels instances; do
        local analyse=()
        [ "$path" = instances ] && analyse=(--instances)
        "$ca" --kitti-root "$dir" --frame 000000 "${analyse[@]}" -o "$dir-$path.json" 2>/dev/null
        local code=0
        "$ca" evaluate --entities "$dir-$path.json" --reference "$scene" --bar-class car \
            --bar-range 30 --min-visible-fraction 0.25 --kitti-root "$dir" --frame 000000 \
            --json "$dir-$path-eval.json" >/dev/null 2>&1 || code=$?
        [ "$code" = 0 ] || [ "$code" = 3 ] || { echo "evaluate failed on $name" >&2; exit 1; }
        evals+=("$set=$path=$name=$dir-$path-eval.json")
    done
}
for seed in $seeds; do
    for kind in parking kerbside pedestrians; do score_street tuning "$kind" "$seed"; done
done
for seed in $held_out_seeds; do
    for kind in parking kerbside pedestrians; do score_street held-out "$kind" "$seed"; done
done

python3 - "${evals[@]}" <<'EOF'
import json, statistics, sys
rows = {}
for arg in sys.argv[1:]:
    street_set, path, name, file = arg.split("=", 3)
    e = json.load(open(file))["entities"]
    bins = e["classes"].get("car", {}).get("bins", {})
    near = [bins.get(b, {}) for b in ("0-10", "10-20", "20-30")]
    cars = [m for m in e["matches"] if m["class"] == "car" and m["range_m"] < 30.0]
    r = rows.setdefault((street_set, path), {"ref": 0, "hit": 0, "spur": 0, "centre": []})
    r["ref"] += sum(b.get("reference", 0) for b in near)
    r["hit"] += sum(b.get("matched", 0) for b in near)
    r["spur"] += sum(b.get("spurious", 0) for b in near)
    if cars:
        r["centre"].append(statistics.median(m["centre_error_m"] for m in cars))
print("| streets | classes from | cars found | spurious cars | median of the streets' median "
      "centre errors, m | streets with a median centre error > 0.3 m |")
print("|---|---|---|---|---|---|")
for (street_set, path), r in rows.items():
    c = r["centre"]
    print(f"| {street_set} ({len(c)}) | {'semantic + instance image' if path == 'instances' else 'semantic image'} "
          f"| {r['hit']}/{r['ref']} | {r['spur']} | {statistics.median(c):.2f} | "
          f"{sum(x > 0.3 for x in c)} |")
EOF

if [ -d "$kitti_root/instance" ]; then
    echo "=== KITTI frames with their instance images (cars within 30 m, GT owed as in evaluate)"
    for image in "$kitti_root"/instance/*.png; do
        f=$(basename "$image" .png)
        "$ca" --kitti-root "$kitti_root" --frame "$f" --instances -o "$out_dir/kitti-$f.json" \
            2>/dev/null
        echo "--- $f"
        "$ca" evaluate --kitti-root "$kitti_root" --frame "$f" \
            --entities "$out_dir/kitti-$f.json" | grep -E "^  (recall|precision)"
    done
else
    echo "evaluate-instances.sh: no KITTI instance images at $kitti_root; KITTI check skipped" >&2
fi
