#!/usr/bin/env bash
# Regenerates samples/rendered/<scene>/ from samples/rendered/scenes/<scene>.json with
# `scene-render sensors` (default sensor model, seed 0) with KITTI's rig (1242x375, the sensors'
# default), as committed; --half renders KITTI's rig at half size (621x188, intrinsics halved)
# into another folder. A scene's extra `scene-render sensors` flags (e.g. --label-bleed 3) are
# in scenes/<scene>.sensors beside it, when there is one.
# usage: scripts/make-rendered-samples.sh [--half] [OUTPUT_DIR]   (default: samples/rendered)
#        SCENE_RENDER=<path> skips the build and uses that binary.
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/common.sh"

size=()
if [ "${1:-}" = "--half" ]; then
    size=(--size 621x188)
    shift
fi
out=${1:-"$STEREOSCENE_ROOT/samples/rendered"}
render=${SCENE_RENDER:-}
if [ -z "$render" ]; then
    build="$STEREOSCENE_ROOT/build"
    stereoscene_build "$build" Release -- scene-render
    render="$build/scene_viewer/scene-render"
fi

for scene in "$STEREOSCENE_ROOT"/samples/rendered/scenes/*.json; do
    name=$(basename "$scene" .json)
    echo "== scene-render sensors: $name" >&2
    extra=()
    [ -f "${scene%.json}.sensors" ] && read -r -a extra <"${scene%.json}.sensors"
    rm -rf "$out/$name.tmp"
    "$render" sensors "$scene" --out "$out/$name.tmp" --frame 000000 --seed 0 "${size[@]}" \
        "${extra[@]}"
    rm -rf "${out:?}/$name"
    mv "$out/$name.tmp" "$out/$name"
done
echo "wrote $(du -sh "$out" | cut -f1) under $out" >&2
