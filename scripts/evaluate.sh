#!/usr/bin/env bash
# Runs the whole evaluation of cloud-analysis (docs/evaluation.md) and prints the tables.
# First the rendered scenes (tuning data): the committed samples/rendered scenes, easy and hard,
# and more parking streets rendered at run time (scripts/make-parking-scene.py, label bleed; some
# with kerbside clutter where nobody parks, some with people standing there too),
# each scored against its truth with the goal's bars and a reason for every miss and every
# spurious box, then analysed again from the stereo pair alone (--semantics geometry) and
# scored with the stereo-only bars. Then the KITTI frames (checks, never tuned on): disparity of the tuned defaults
# vs OpenCV's sample settings, car entities vs the instance ground truth (with reasons), the
# ground plane, the thesis's one-per-class extractors, and the stereo-only path (--semantics
# geometry: the semantic image ignored; docs/stereo-only.md) beside them; last the KITTI
# frames without an instance image, stereo only, against the hand-drawn 2D boxes of
# samples/labels-2d/kitti15.json.
# usage: scripts/evaluate.sh [--no-build] [--build-dir DIR] [--kitti-root DIR] [--out DIR]
#            [--parking-seeds "2 4 5 ... 12 23 ... 32"] [--kerbside-seeds "2 ... 9 23 ... 32"]
#            [--pedestrian-seeds "2 ... 9"] [--held-out-seeds "13 14 15 16 17 18 19 20 21 22"]
#            [--class-config FILE] [--analysis "FLAGS"] [frames...]
#   --parking-seeds: parking streets (make-parking-scene.py), tuning data
#   --kerbside-seeds: streets with kerbside clutter (make-parking-scene.py --kerbside)
#   --pedestrian-seeds: kerbside streets with groups of people on the sidewalk
#                       (make-parking-scene.py --kerbside --pedestrians); their totals are
#                       printed apart
#   --held-out-seeds: a parking, a kerbside and a pedestrian street each, never used to choose
#                     a parameter; their totals are printed apart from the tuning scenes
#   --class-config: per-class extractor settings for every analysis (to compare settings)
#   --analysis: more flags for every analysis (e.g. "--matcher sgm", to compare settings)
#   default frames: 000000_10 000001_10; default KITTI root: ../shared/data/kitti15
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/common.sh"

build=1
build_dir="$STEREOSCENE_ROOT/build"
kitti_root="$STEREOSCENE_ROOT/../shared/data/kitti15"
out_dir=""
frames=()
# parking_seeds, kerbside_seeds, pedestrian_seeds, held_out_seeds
source "$STEREOSCENE_ROOT/scripts/street-seeds.sh"
analysis_args=()
while [ $# -gt 0 ]; do
    case "$1" in
        --no-build) build=0 ;;
        --build-dir) build_dir=$2; shift ;;
        --kitti-root) kitti_root=$2; shift ;;
        --out) out_dir=$2; shift ;;
        --parking-seeds) parking_seeds=$2; shift ;;
        --kerbside-seeds) kerbside_seeds=$2; shift ;;
        --pedestrian-seeds) pedestrian_seeds=$2; shift ;;
        --held-out-seeds) held_out_seeds=$2; shift ;;
        --class-config) analysis_args+=(--class-config "$2"); shift ;;
        --analysis) read -r -a more <<<"$2"; analysis_args+=("${more[@]}"); shift ;;
        -h|--help) sed -n '2,27p' "$0"; exit 0 ;;
        *) frames+=("$1") ;;
    esac
    shift
done
[ ${#frames[@]} -gt 0 ] || frames=(000000_10 000001_10)

if [ "$build" = 1 ]; then
    stereoscene_build "$build_dir" Release -- cloud-analysis scene-render
fi
ca="$build_dir/cloud_analysis/cloud-analysis"
[ -n "$out_dir" ] || out_dir="$build_dir/evaluation"
mkdir -p "$out_dir"

# The rendered scenes: the goal's bars, and the stereo-only bars (goal, stereo_only_goal).
source "$STEREOSCENE_ROOT/scripts/street-bars.sh"
stereo_only_evals=()
rendered=()
for dir in "$STEREOSCENE_ROOT"/samples/rendered/*/; do
    name=$(basename "$dir")
    [ -f "$STEREOSCENE_ROOT/samples/rendered/scenes/$name.json" ] && rendered+=("$name")
done
mkdir -p "$out_dir/rendered"
render_street() {  # kind name seed [make-parking-scene.py flags]; kind: run (tuning) or held
    local kind=$1 name=$2 seed=$3
    shift 3
    local scene="$out_dir/rendered/$name.json"
    python3 "$STEREOSCENE_ROOT/scripts/make-parking-scene.py" --seed "$seed" "$@" -o "$scene"
    "$build_dir/scene_viewer/scene-render" sensors "$scene" --out "$out_dir/rendered/$name" \
        --frame 000000 --seed "$seed" --label-bleed 3
    rendered+=("$kind:$name")
}
for seed in $parking_seeds; do render_street run "parking-street-$seed" "$seed"; done
for seed in $kerbside_seeds; do render_street run "kerbside-$seed" "$seed" --kerbside; done
for seed in $pedestrian_seeds; do
    render_street run "pedestrians-$seed" "$seed" --kerbside --pedestrians
done
for seed in $held_out_seeds; do
    render_street held "parking-street-$seed" "$seed"
    render_street held "kerbside-$seed" "$seed" --kerbside
    render_street held "pedestrians-$seed" "$seed" --kerbside --pedestrians
done
echo "=== rendered scenes (tuning data, then the held-out streets) ==="
evals=()
for r in "${rendered[@]}"; do
    if [ "${r#run:}" != "$r" ] || [ "${r#held:}" != "$r" ]; then
        name=${r#*:}
        dir="$out_dir/rendered/$name"
        truth="$out_dir/rendered/$name.json"
        label="$name (seed, rendered now)"
        [ "${r#held:}" = "$r" ] || label="$name (held out, rendered now)"
    else
        name=$r
        dir="$STEREOSCENE_ROOT/samples/rendered/$name"
        truth="$STEREOSCENE_ROOT/samples/rendered/scenes/$name.json"
        label="$name (committed)"
    fi
    base="$out_dir/rendered-$name"
    "$ca" --kitti-root "$dir" --frame 000000 -o "$base.json" "${analysis_args[@]}" \
        2>"$base.log"
    code=0
    "$ca" evaluate --entities "$base.json" --reference "$truth" "${goal[@]}" \
        --min-visible-fraction 0.25 --kitti-root "$dir" --frame 000000 --json "$base-eval.json" \
        >"$base-eval.txt" 2>&1 || code=$?
    [ "$code" = 0 ] || [ "$code" = 3 ] || { cat "$base-eval.txt" >&2; exit 1; }
    echo "--- $label"
    grep -E "^  (bars|why)" "$base-eval.txt" || true
    evals+=("$label=$base-eval.json")
    # The same scene from the stereo pair alone, with the stereo-only bars.
    "$ca" --kitti-root "$dir" --frame 000000 --semantics geometry -o "$base-stereo-only.json" \
        "${analysis_args[@]}" 2>"$base-stereo-only.log"
    code=0
    "$ca" evaluate --entities "$base-stereo-only.json" --reference "$truth" "${stereo_only_goal[@]}" \
        --min-visible-fraction 0.25 --kitti-root "$dir" --frame 000000 \
        --json "$base-stereo-only-eval.json" >"$base-stereo-only-eval.txt" 2>&1 || code=$?
    [ "$code" = 0 ] || [ "$code" = 3 ] || { cat "$base-stereo-only-eval.txt" >&2; exit 1; }
    echo "--- $label, stereo only (--semantics geometry)"
    grep -E "^  (bars|why)" "$base-stereo-only-eval.txt" || true
    stereo_only_evals+=("$label=$base-stereo-only-eval.json")
done
python3 - "${evals[@]}" -- "${stereo_only_evals[@]}" <<'PY'
import json, statistics, sys
args = sys.argv[1:]
split = args.index("--")
tables = [("labelled (the goal's bars)", args[:split]),
          ("stereo only (--semantics geometry; the stereo-only bars)", args[split + 1:])]
for title, paths in tables:
  print(f"{title}:")
  print("| scene | cars <= 30 m scored | found | spurious cars | precision | median centre m "
        "| median heading deg | BEV IoU >= 0.5 | goal |")
  print("|---|---|---|---|---|---|---|---|---|")
  totals = {}  # per group (tuning, held out): its matched cars and counts
  for arg in paths:
    label, path = arg.rsplit("=", 1)
    d = json.load(open(path))
    e = d["entities"]
    bins = e["classes"].get("car", {}).get("bins", {})
    near = [bins.get(b, {}) for b in ("0-10", "10-20", "20-30")]
    ref = sum(b.get("reference", 0) for b in near)
    hit = sum(b.get("matched", 0) for b in near)
    spur = sum(b.get("spurious", 0) for b in near)
    good = sum(b.get("good_iou", 0) for b in near)
    cars = [m for m in e["matches"] if m["class"] == "car" and m["range_m"] < 30.0]
    group = "held out" if "held out" in label else "tuning"
    if label.startswith("pedestrians-"):
      group = "pedestrian streets, " + group  # apart: the other totals keep their scenes
    t = totals.setdefault(group,
                          {"cars": [], "ref": 0, "hit": 0, "spur": 0, "good": 0, "scenes": 0,
                           "met": 0, "on_person": 0})
    t["on_person"] += sum(1 for x in e.get("diagnosis", [])
                          if x["id"].startswith("car-") and x["kind"] == "phantom"
                          and "person" in x["reason"])
    t["cars"] += cars
    for key, n in (("ref", ref), ("hit", hit), ("spur", spur), ("good", good), ("scenes", 1),
                   ("met", int(d["bars"]["pass"]))):
      t[key] += n
    centre = f"{statistics.median([m['centre_error_m'] for m in cars]):.2f}" if cars else "-"
    head = f"{statistics.median([m['heading_error_deg'] for m in cars]):.1f}" if cars else "-"
    prec = f"{hit / (hit + spur):.2f}" if hit + spur else "-"
    print(f"| {label} | {ref} | {hit} | {spur} | {prec} | {centre} | {head} | {good}/{ref} | "
          f"{'met' if d['bars']['pass'] else 'missed'} |")
  for group, t in totals.items():
    if not t["cars"]:
      continue
    errors = [m["centre_error_m"] for m in t["cars"]]
    print(f"{group}, {t['scenes']} scenes: {t['hit']} of {t['ref']} cars found, {t['spur']} "
          f"spurious cars <= 30 m, bars met on {t['met']}; matched cars: median centre error "
          f"{statistics.median(errors):.3f} m, mean {statistics.mean(errors):.3f} m, mean BEV IoU "
          f"{statistics.mean([m['bev_iou'] for m in t['cars']]):.3f}"
          + (f"; {t['on_person']} car boxes on or beside a person (any range)"
             if group.startswith("pedestrian") else ""))
    # The same cars read as one set rather than street by street: precision, median heading
    # error and the share of the scored cars with BEV IoU >= 0.5.
    print(f"  {group}, as one set: precision {t['hit'] / max(t['hit'] + t['spur'], 1):.3f}, "
          f"median heading error "
          f"{statistics.median([m['heading_error_deg'] for m in t['cars']]):.1f} deg, "
          f"BEV IoU >= 0.5 for {t['good']} of {t['ref']} ({t['good'] / max(t['ref'], 1):.2f})")
PY

# The real drive against the hand-drawn 2D boxes (skipped without ../shared/data).
"$STEREOSCENE_ROOT/scripts/evaluate-real-drive.sh" --no-build --build-dir "$build_dir" \
    --out "$out_dir/real-drive" -- "${analysis_args[@]}"

if [ ! -d "$kitti_root/disp_occ_0" ] || [ ! -d "$kitti_root/instance" ]; then
    echo "evaluate.sh: no KITTI data at $kitti_root (needs image_2 image_3 semantic_rgb disp_occ_0 instance calib); KITTI checks skipped" >&2
    exit 0
fi
echo "=== KITTI frames (checks) ==="
for f in "${frames[@]}"; do
    echo "=== frame $f ==="
    for preset in tuned opencv-sample; do
        "$ca" --kitti-root "$kitti_root" --frame "$f" --preset "$preset" "${analysis_args[@]}" \
            -o "$out_dir/$f-$preset.json" --disparity-kitti "$out_dir/$f-$preset-disp.png" 2>"$out_dir/$f-$preset.log"
        echo "--- disparity preset: $preset"
        "$ca" evaluate --kitti-root "$kitti_root" --frame "$f" \
            --entities "$out_dir/$f-$preset.json" --disparity "$out_dir/$f-$preset-disp.png" \
            --json "$out_dir/$f-$preset-eval.json"
        # The same entities with whole GT masks and no 2D fallback, for comparison.
        "$ca" evaluate --kitti-root "$kitti_root" --frame "$f" \
            --entities "$out_dir/$f-$preset.json" --occluder-gap 0 --fallback-max-points -1 \
            --json "$out_dir/$f-$preset-eval-oldrule.json" >/dev/null
    done
    # The stereo-only path: tuned disparity, classes from the geometry, the semantic image unread.
    "$ca" --kitti-root "$kitti_root" --frame "$f" --semantics geometry "${analysis_args[@]}" \
        -o "$out_dir/$f-stereo-only.json" --disparity-kitti "$out_dir/$f-stereo-only-disp.png" \
        --semantic-out "$out_dir/$f-stereo-only-semantic.png" 2>"$out_dir/$f-stereo-only.log"
    echo "--- stereo only (--semantics geometry), tuned disparity"
    "$ca" evaluate --kitti-root "$kitti_root" --frame "$f" \
        --entities "$out_dir/$f-stereo-only.json" --disparity "$out_dir/$f-stereo-only-disp.png" \
        --json "$out_dir/$f-stereo-only-eval.json"
    "$ca" evaluate --kitti-root "$kitti_root" --frame "$f" \
        --entities "$out_dir/$f-stereo-only.json" --occluder-gap 0 --fallback-max-points -1 \
        --json "$out_dir/$f-stereo-only-eval-oldrule.json" >/dev/null
    if [ -f "$kitti_root/semantic_rgb/$f.png" ]; then
        "$ca" score-semantics --estimate "$out_dir/$f-stereo-only-semantic.png" \
            --truth "$kitti_root/semantic_rgb/$f.png" --json "$out_dir/$f-stereo-only-semantic.json"
    fi
    echo "--- thesis extractors (one entity per class), tuned disparity"
    for method in centroid average variance; do
        "$ca" --kitti-root "$kitti_root" --frame "$f" --method "$method" \
            -o "$out_dir/$f-$method.json" 2>"$out_dir/$f-$method.log"
        /usr/bin/python3 - "$out_dir/$f-$method.json" "$method" <<'PY'
import json, sys
doc = json.load(open(sys.argv[1]))
cars = [e for e in doc["entities"] if e["class"] == "car"]
line = ", ".join(f'{e["class"]}' for e in doc["entities"])
print(f"  {sys.argv[2]:9s} {len(doc['entities']):2d} entities ({line})")
for e in cars:
    print(f"            car: x {e['x']:.2f} y {e['y']:.2f} z {e['z']:.2f} L {e['L']:.2f} W {e['W']:.2f} H {e['H']:.2f} ({e['point_count']} points)")
PY
    done
done

echo "=== summary over ${frames[*]} ==="
/usr/bin/python3 - "$out_dir" "${frames[@]}" <<'PY'
import json, sys, os
out, frames = sys.argv[1], sys.argv[2:]
def cars(preset, suffix=""):
    t = {"gt_owed": 0, "gt_owed_matched": 0, "entities_in_range": 0, "entities_matched": 0,
         "entities_unscorable": 0, "fallback_matched": 0}
    for f in frames:
        ev = json.load(open(os.path.join(out, f"{f}-{preset}-eval{suffix}.json")))
        for k in t:
            t[k] += ev["cars"][k]
    rec = t["gt_owed_matched"] / t["gt_owed"] if t["gt_owed"] else 1.0
    prec = t["entities_matched"] / t["entities_in_range"] if t["entities_in_range"] else 1.0
    scor = t["entities_in_range"] - t["entities_unscorable"]
    prec_s = t["entities_matched"] / scor if scor else 1.0
    return (f"recall {t['gt_owed_matched']}/{t['gt_owed']} = {100*rec:.1f} %, "
            f"precision {t['entities_matched']}/{t['entities_in_range']} = {100*prec:.1f} % "
            f"(scorable {t['entities_matched']}/{scor} = {100*prec_s:.1f} %; "
            f"{t['fallback_matched']} matched by the 2D fallback)")

for preset in ("tuned", "opencv-sample", "stereo-only"):
    d1, dens, heights = [], [], []
    for f in frames:
        ev = json.load(open(os.path.join(out, f"{f}-{preset}-eval.json")))
        d1.append(ev["disparity"]["d1_all"])
        dens.append(ev["disparity"]["density"])
        if "ground_plane" in ev:
            heights.append(ev["ground_plane"]["camera_height_m"])
    print(f"{preset:14s} D1-all " + " / ".join(f"{100*x:.2f} %" for x in d1) +
          "   density " + " / ".join(f"{100*x:.1f} %" for x in dens))
    print(f"{'':14s} cars: " + cars(preset))
    print(f"{'':14s} cars, whole GT masks, no 2D fallback: " +
          cars(preset, "-oldrule"))
    print(f"{'':14s} camera height above the fitted road plane: " +
          " / ".join(f"{h:.3f} m" for h in heights))
for f in frames:
    path = os.path.join(out, f"{f}-stereo-only-semantic.json")
    if os.path.exists(path):
        sc = json.load(open(path))
        iou = ", ".join(f"{k} {v:.3f}" if v is not None else f"{k} -" for k, v in sc["iou"].items())
        print(f"stereo-only semantic image {f}: pixel accuracy {sc['accuracy']:.3f}, IoU {iou}")

print("GT cars (docs/evaluation.md 'Cars'): mask pixels, GT disparity pixels kept as the car's "
      "own surface / dropped as occluders, range of the kept points' centroid")
for f in frames:
    ev = json.load(open(os.path.join(out, f"{f}-tuned-eval.json")))
    old = {c["instance"]: c for c in
           json.load(open(os.path.join(out, f"{f}-tuned-eval-oldrule.json")))["cars"]["gt_cars"]}
    for c in ev["cars"]["gt_cars"]:
        o = old[c["instance"]]
        rng = f"{c['range_m']:5.1f}" if c["range_m"] is not None else "    -"
        orng = f"{o['range_m']:5.1f}" if o["range_m"] is not None else "    -"
        print(f"  {f} car {c['instance']:2d}: mask {c['mask_pixels']:6d}  GT {o['pixels']:5d} -> "
              f"kept {c['pixels']:5d} dropped {c['occluder_pixels']:4d}  range {orng} -> {rng} m"
              f"  owed {'yes' if o['owed'] else 'no '} -> {'yes' if c['owed'] else 'no'}"
              f"  match {o['entity'] or '-'} -> {c['entity'] or '-'} {c['rule']}")
PY

# The KITTI frames without an instance image, stereo only, against the project's hand-drawn 2D
# boxes (samples/labels-2d/kitti15.json).
labels_2d="$STEREOSCENE_ROOT/samples/labels-2d/kitti15.json"
mkdir -p "$out_dir/labels-2d"
labelled=0
for f in $(/usr/bin/python3 -c 'import json, sys; print(" ".join(x["frame"] for x in json.load(open(sys.argv[1]))["frames"]))' "$labels_2d"); do
    [ -f "$kitti_root/image_2/$f.png" ] || continue
    "$ca" --kitti-root "$kitti_root" --frame "$f" --semantics geometry "${analysis_args[@]}" \
        -o "$out_dir/labels-2d/$f.json" 2>"$out_dir/labels-2d/$f.log"
    labelled=$((labelled + 1))
done
if [ "$labelled" -gt 0 ]; then
    echo "=== KITTI frames without instance images, stereo only, against the hand-drawn 2D boxes ==="
    "$ca" evaluate --entities "$out_dir/labels-2d" --labels-2d "$labels_2d" \
        --json "$out_dir/labels-2d-eval.json"
fi

