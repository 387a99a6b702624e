#!/usr/bin/env bash
# Builds Release and runs the benchmarks (scripts/bench.py): per-stage table beside
# the OpenCV matcher alone, batch fps and memory over 100 frames, presets with their accuracy,
# scaling plots. Prints Markdown tables; writes OUT_DIR/bench.json. A benchmark, not a test.
# usage: scripts/bench.sh [BUILD_DIR] [OUT_DIR] [bench.py flags, e.g. --parts table --runs 9]
#        (defaults: build, out/bench; --plots docs/images writes the perf_*.png of the docs)
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/common.sh"

build=${1:-"$STEREOSCENE_ROOT/build"}
out=${2:-"$STEREOSCENE_ROOT/out/bench"}
shift $(($# > 2 ? 2 : $#))
stereoscene_build "$build" Release -- cloud-analysis
# scene-render's rows are added when it builds (the cloud-analysis rows do not need it).
stereoscene_build "$build" Release -- scene-render || echo "bench: scene-render did not build" >&2
mkdir -p "$out"
exec /usr/bin/python3 "$STEREOSCENE_ROOT/scripts/bench.py" --build "$build" --out "$out" "$@"
