#!/usr/bin/env bash
# Installs what is missing, builds, and runs the whole test suite through CTest.
# usage: scripts/test.sh [--sanitize] [extra ctest arguments...]
#   --sanitize   build with AddressSanitizer + UndefinedBehaviorSanitizer (in build-sanitize/)
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/common.sh"

sanitize=OFF
ctest_args=()
for arg in "$@"; do
    case "$arg" in
        --sanitize) sanitize=ON ;;
        -h|--help) sed -n '2,4p' "$0"; exit 0 ;;
        *) ctest_args+=("$arg") ;;
    esac
done

if [ "$sanitize" = ON ]; then
    build_dir="$STEREOSCENE_ROOT/build-sanitize"
    build_type=RelWithDebInfo
    # Leak checking is off: Mesa and GLVND keep allocations alive until exit by design.
    export ASAN_OPTIONS=detect_leaks=0:abort_on_error=1
    export UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1
else
    build_dir="$STEREOSCENE_ROOT/build"
    build_type=Release
fi

stereoscene_build "$build_dir" "$build_type" -DSTEREOSCENE_BUILD_TESTS=ON \
    -DSTEREOSCENE_SANITIZE="$sanitize"
ctest --test-dir "$build_dir" --output-on-failure --parallel "$(nproc)" --timeout 600 "${ctest_args[@]}"
