#!/usr/bin/env bash
# Builds the Debian package with cpack and checks its contents and dependencies with dpkg-deb
# (the package is not installed: that would change the machine).
# usage: deb_check.sh BUILD_DIR WORK VERSION
set -euo pipefail
build=$1 work=$2 version=$3
fail() {
    echo "FAIL: $*" >&2
    exit 1
}

rm -rf "$work"
mkdir -p "$work"
cpack --config "$build/CPackConfig.cmake" -G DEB -B "$work" >"$work/cpack.log" 2>&1 ||
    fail "cpack failed: $(tail -5 "$work/cpack.log")"
debs=("$work"/*.deb)
[ ${#debs[@]} = 1 ] && [ -f "${debs[0]}" ] || fail "cpack made ${#debs[@]} packages"
contents=$(dpkg-deb -c "${debs[0]}" | awk '{print $NF}')
for f in ./usr/bin/cloud-analysis ./usr/bin/scene-render \
    ./usr/share/stereoscene/schema/entities.schema.json \
    ./usr/share/stereoscene/assets/classes/render_classes.json \
    ./usr/share/stereoscene/assets/palettes/cityscapes.json \
    ./usr/share/stereoscene/assets/models/car.glb \
    ./usr/share/stereoscene/samples/synthetic/left.png \
    ./usr/share/stereoscene/web/viewer.js ./usr/share/stereoscene/web/viewer_util.js; do
    grep -qxF "$f" <<<"$contents" || fail "the package lacks $f"
done
! grep -qE '^\./usr/(include|lib)/' <<<"$contents" ||
    fail "the package carries headers or libraries: $(grep -E '^\./usr/(include|lib)/' <<<"$contents" | head -3)"

fields=$(dpkg-deb -f "${debs[0]}" Package Version Depends)
for want in "Package: stereoscene" "Version: $version" libopencv-core libegl-mesa0 \
    libgl1-mesa-dri libopengl0; do
    grep -qF "$want" <<<"$fields" || fail "the package's control fields lack '$want': $fields"
done
rm -rf "$work"
