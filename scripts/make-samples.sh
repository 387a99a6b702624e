#!/bin/sh
# Regenerates samples/synthetic/ with the project's own synthetic scene renderer.
# Usage: scripts/make-samples.sh [BUILD_DIR]   (default: build)
set -eu
here=$(cd "$(dirname "$0")/.." && pwd)
build=${1:-"$here/build"}
tool="$build/cloud_analysis/cloud-analysis"
[ -x "$tool" ] || { echo "make-samples: error: build cloud-analysis first ($tool)" >&2; exit 1; }
cd "$here"
out=samples/synthetic
"$tool" make-sample --out "$out" --seed 1
# A reference run of the default pipeline on it, for docs and the CLI tests' eyes.
"$tool" --left "$out/left.png" --right "$out/right.png" --semantic "$out/semantic.png" \
    --calib "$out/calib.yaml" --frame synthetic-street -o "$out/expected_entities.json"
echo "make-samples: wrote $out" >&2
