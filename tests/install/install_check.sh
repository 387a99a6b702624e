#!/usr/bin/env bash
# Installs the build to a temporary prefix, moves the install elsewhere, and runs both tools
# from an unrelated folder on the installed sample: cloud-analysis makes an entity file,
# scene-render draws it. Then it takes files out of the moved install to prove that the tools
# read the assets of the install they run from (not the source tree).
# usage: install_check.sh BUILD_DIR WORK VIEWER_THREE(ON|OFF)
set -euo pipefail
build=$1 work=$2 viewer_three=$3
expect=$(dirname "$0")/../cli/expect.sh
fail() {
    echo "FAIL: $*" >&2
    exit 1
}

rm -rf "$work"
mkdir -p "$work/elsewhere"
cmake --install "$build" --prefix "$work/first" >/dev/null
mv "$work/first" "$work/moved"
bin=$work/moved/bin
share=$work/moved/share/stereoscene
sample=$share/samples/synthetic
for f in bin/cloud-analysis bin/scene-render share/stereoscene/schema/entities.schema.json \
    share/stereoscene/assets/classes/render_classes.json \
    share/stereoscene/assets/palettes/cityscapes.json share/stereoscene/assets/models/car.glb; do
    [ -e "$work/moved/$f" ] || fail "the install lacks $f"
done

cd "$work/elsewhere"
analyse=("$bin/cloud-analysis" --left "$sample/left.png" --right "$sample/right.png"
    --semantic "$sample/semantic.png" --calib "$sample/calib.yaml" --frame synthetic-street)
"${analyse[@]}" -o entities.json
count() { python3 -c 'import json, sys; print(len(json.load(open(sys.argv[1]))["entities"]))' "$1"; }
got=$(count entities.json) expected=$(count "$sample/expected_entities.json")
[ "$got" = "$expected" ] && [ "$got" -gt 0 ] || fail "$got entities, the sample expects $expected"
bash "$expect" --code 0 --output "$PWD/render.png" -- \
    "$bin/scene-render" entities.json -o render.png --size 160x90

# The browser viewer's folder from the install's web files (three.js is bundled only where npm
# installed it: scripts/install-deps.sh).
if [ "$viewer_three" = ON ]; then
    bash "$expect" --code 0 --output "$PWD/viewer/index.html" --magic 3c21646f6374797065 -- \
        "$bin/scene-render" html entities.json --out viewer
fi

# Without the moved install's palette and class table the tools fail naming those files.
rm "$share/assets/palettes/cityscapes.json" "$share/assets/classes/render_classes.json"
bash "$expect" --code 1 --stderr "$share/assets/palettes/cityscapes.json" \
    --output "$PWD/again.json" --exists 0 -- "${analyse[@]}" -o again.json
bash "$expect" --code 1 --stderr "$share/assets/classes/render_classes.json" \
    --output "$PWD/again.png" --exists 0 -- "$bin/scene-render" entities.json -o again.png
cd /
rm -rf "$work"
