#!/usr/bin/env bash
# scene-render html on a drive: a three-frame drive (scene-render sensors --frames) becomes a
# viewer folder with one script per frame and its left images; the drive's bad inputs exit with
# one line naming the file or flag and write no folder.
# usage: html_drive.sh SCENE_RENDER DRIVE_SCENE
set -euo pipefail
render=$1 scene=$2
d=$(mktemp -d)
trap 'rm -rf "$d"' EXIT

"$render" sensors "$scene" --out "$d/drive" --frames 3 --fps 10 --size 160x48
truth=$d/drive/truth
"$render" html "$truth" --backgrounds "$d/drive/image_2" --trail 5 --out "$d/viewer"
for f in index.html viewer_drive.js models.glb data/models-glb.js frames/000000.js \
    frames/000002.js frames/000002.png; do
    test -s "$d/viewer/$f" || { echo "missing $f"; exit 1; }
done
grep -q '"trail_frames":5' "$d/viewer/data/scene-data.js"
# The index file itself names the drive as well as its folder.
"$render" html "$truth/sequence.json" --out "$d/viewer-index"
test -s "$d/viewer-index/frames/000002.js"

# expect CODE PATTERN OUT ARGS...: the exit code, one stderr line matching PATTERN, no OUT.
expect() {
    local code=$1 pattern=$2 out=$3
    shift 3
    set +e
    "$render" html "$@" --out "$out" 2> "$d/err"
    local got=$?
    set -e
    cat "$d/err"
    test "$got" = "$code" || { echo "exit $got, expected $code"; exit 1; }
    test "$(wc -l < "$d/err")" = 1 || { echo "not one stderr line"; exit 1; }
    grep -qE -e "^scene-render: error: .*$pattern" "$d/err" || { echo "no '$pattern'"; exit 1; }
    test ! -e "$out" || { echo "$out was written"; exit 1; }
}
frame0=$(ls "$truth" | grep -v sequence | head -1)
expect 2 "$frame0: .*a drive is shown alone" "$d/o1" "$truth" "$truth/$frame0"
expect 2 "--cloud: .*not with a drive" "$d/o2" "$truth" --cloud "$d/none.ply"
expect 2 "--backgrounds: .*needs a drive" "$d/o3" "$truth/$frame0" --backgrounds "$d/drive/image_2"
expect 2 "--trail: .*must be in" "$d/o4" "$truth" --trail -1
mkdir "$d/no-images"
expect 1 "no-images/${frame0%.json}.png: cannot read background image" "$d/o5" "$truth" \
    --backgrounds "$d/no-images"
mkdir "$d/gif"
for f in "$d/drive/image_2"/*.png; do printf 'GIF89a' > "$d/gif/$(basename "$f")"; done
expect 1 "cannot read background image: neither PNG nor JPEG" "$d/o6" "$truth" --backgrounds "$d/gif"
cp -r "$truth" "$d/broken"
echo '{"schema_version": "1.1.0", "frame": ' > "$d/broken/$frame0"
expect 1 "broken/$frame0: invalid entity file" "$d/o7" "$d/broken"
echo "html drive: ok"
