#!/usr/bin/env bash
# The drive loop on the committed short drive: scene-render sensors --frames renders it with
# its truth, cloud-analysis batch analyses every frame, track follows the cars, evaluate-tracks
# scores them with the bars given after the folder; then the bad inputs of a drive: an
# unreadable frame in the middle and a timestamp going back.
# usage: drive_loop.sh SCENE_RENDER CLOUD_ANALYSIS SCENE FRAMES [evaluate-tracks bars...]
set -euo pipefail
render=$1 analyse=$2 scene=$3 frames=$4
shift 4
d=$(mktemp -d)
trap 'rm -rf "$d"' EXIT

"$render" sensors "$scene" --out "$d/drive" --frames "$frames" --fps 10
test "$(ls "$d/drive/image_2" | wc -l)" = "$frames"
ls "$d/drive/image_2" | sed 's/\.png$//' > "$d/frames.txt"
mkdir "$d/analysed"
"$analyse" batch --kitti-root "$d/drive" --list "$d/frames.txt" --out-dir "$d/analysed" --quiet
"$analyse" track "$d/analysed" --out-dir "$d/tracked" --fps 10 2> "$d/track.err"
grep -q "track: $frames of $frames frames" "$d/track.err"
grep -q '"track_id"' "$d/tracked/0000000003.json"
grep -q '"velocity"' "$d/tracked/0000000007.json"
"$analyse" evaluate-tracks --tracks "$d/tracked" --truth "$d/drive/truth" \
    --visibility "$d/drive/visibility" --min-visible-fraction 0.25 "$@" | tee "$d/eval.txt"
grep -q "^car      all" "$d/eval.txt"

# The same drive as a KITTI raw folder (image_02/data, image_03/data, timestamps.txt, the
# calibration in the date folder above) tracked inside batch: the same track ids as
# batch + track writing each frame at once (--lag 0: batch --track is live, so it neither turns
# nor reports a track in frames already written).
"$analyse" track "$d/analysed" --out-dir "$d/tracked-live" --fps 10 --lag 0 --quiet
raw=$d/raw/2011_09_26/drive_sync
mkdir -p "$raw/image_02/data" "$raw/image_03/data"
cp "$d/drive/image_2/"*.png "$raw/image_02/data/"
cp "$d/drive/image_3/"*.png "$raw/image_03/data/"
cp "$d/drive/calib/calib_cam_to_cam.txt" "$d/raw/2011_09_26/"
for i in $(seq 0 $((frames - 1))); do printf '2011-09-26 13:02:25.%d00000000\n' "$i"; done \
    > "$raw/image_02/timestamps.txt"
"$analyse" batch --drive "$raw" --semantic-dir "$d/drive/semantic_rgb" --track \
    --out-dir "$d/raw-tracked" --quiet
python3 - "$d/tracked-live" "$d/raw-tracked" <<'PY'
import json, os, sys
a, b = sys.argv[1:3]
index = json.load(open(os.path.join(b, "sequence.json")))
assert index["id"] == "drive_sync", index["id"]
times = [f["timestamp"] for f in index["frames"]]
assert abs(times[1] - times[0] - 0.1) < 1e-6, times
for f in index["frames"]:
    ids = lambda d: sorted((e["id"], e.get("track_id", -1)) for e in json.load(open(os.path.join(d, f["file"])))["entities"])
    assert ids(a) == ids(b), (f["file"], ids(a), ids(b))
print("batch --drive --track: the same tracks as batch + track over", len(times), "frames")
PY
# A list of pairs, and the flags that do not go together (exit 2, nothing written).
(cd "$d/drive" && ls image_2 | sed 's#.*#image_2/& image_3/& semantic_rgb/&#') > "$d/drive/pairs.txt"
"$analyse" batch --pairs "$d/drive/pairs.txt" --calib "$d/drive/calib/calib_cam_to_cam.txt" \
    --track --out-dir "$d/pairs-tracked" --quiet
test "$(grep -c '"file"' "$d/pairs-tracked/sequence.json")" = "$frames"
# The list named by a bare file name, from its own folder: the drive takes the folder's name.
(cd "$d/drive" && "$analyse" batch --pairs pairs.txt --calib calib/calib_cam_to_cam.txt \
    --track --out-dir "$d/pairs-bare" --quiet)
grep -q '"id": "drive"' "$d/pairs-bare/sequence.json"
# The tracker's settings reach the tracker inside batch as they do `track`.
"$analyse" track "$d/analysed" --out-dir "$d/tracked-open" --fps 10 --gate-chi2 0 \
    --coast-min-hits 0 --coast 4 --lag 0 --quiet
"$analyse" batch --kitti-root "$d/drive" --list "$d/frames.txt" --track --fps 10 --gate-chi2 0 \
    --coast-min-hits 0 --coast 4 --out-dir "$d/batch-tracked-open" --quiet
for f in "$d/tracked-open/"0*.json; do
    python3 - "$f" "$d/batch-tracked-open/$(basename "$f")" <<'PY'
import json, sys
boxes = lambda p: sorted((e["id"], e.get("track_id", -1), round(e["x"], 6), round(e["z"], 6))
                         for e in json.load(open(p))["entities"])
assert boxes(sys.argv[1]) == boxes(sys.argv[2]), sys.argv[1:]
PY
done
for bad in "--pairs $d/drive/pairs.txt" "--drive $raw --track --resume" "--drive $raw --evaluate" \
    "--kitti-root $d/drive --frames 0000000000 --semantic-dir $d"; do
    set +e
    # shellcheck disable=SC2086
    "$analyse" batch $bad --out-dir "$d/refused" 2> "$d/refused.err"
    code=$?
    set -e
    cat "$d/refused.err"
    test "$code" = 2 && test ! -e "$d/refused"
done

# An unreadable frame in the middle: named on stderr, exit 1, every other frame tracked and
# listed in a valid index.
cp -r "$d/analysed" "$d/broken"
echo '{"schema_version": "1.1.0", "frame": ' > "$d/broken/0000000002.json"
set +e
"$analyse" track "$d/broken" --out-dir "$d/tracked-broken" 2> "$d/broken.err"
code=$?
set -e
cat "$d/broken.err"
test "$code" = 1
grep -q "0000000002.json: .*(frame 2 skipped)" "$d/broken.err"
test ! -e "$d/tracked-broken/0000000002.json"
test -s "$d/tracked-broken/0000000003.json"
test "$(grep -c '"file"' "$d/tracked-broken/sequence.json")" = "$((frames - 1))"

# Time going back (frame 3 says it was taken before frame 2): a warning naming the frame, the
# tracker restarts, every frame is written.
cp -r "$d/analysed" "$d/back"
python3 - "$d/back/0000000003.json" <<'PY'
import json, sys
doc = json.load(open(sys.argv[1]))
doc["frame"]["timestamp"] = 0.05
json.dump(doc, open(sys.argv[1], "w"))
PY
"$analyse" track "$d/back" --out-dir "$d/tracked-back" 2> "$d/back.err"
cat "$d/back.err"
grep -q "warning: 0000000003.json: timestamp 0.05.* is not after the previous" "$d/back.err"
grep -q "1 restarts" "$d/back.err"
test "$(grep -c '"file"' "$d/tracked-back/sequence.json")" = "$frames"
echo "drive loop: ok"
