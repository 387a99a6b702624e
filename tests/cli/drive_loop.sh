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
