# Shared by demo.sh, test.sh and bench.sh: install what is missing, configure and build.
# usage: source scripts/common.sh; stereoscene_build <build-dir> <build-type> [cmake args...] [-- targets...]

STEREOSCENE_ROOT=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)

stereoscene_build() {
    local build_dir=$1 build_type=$2
    shift 2
    local cmake_args=() targets=()
    while [ $# -gt 0 ]; do
        if [ "$1" = "--" ]; then
            shift
            targets=("$@")
            break
        fi
        cmake_args+=("$1")
        shift
    done
    "$STEREOSCENE_ROOT/scripts/install-deps.sh"
    local generator=()
    [ -f "$build_dir/CMakeCache.txt" ] || generator=(-G Ninja)
    cmake -S "$STEREOSCENE_ROOT" -B "$build_dir" "${generator[@]}" \
        -DCMAKE_BUILD_TYPE="$build_type" "${cmake_args[@]}" >&2
    local target_args=()
    for t in "${targets[@]}"; do target_args+=(--target "$t"); done
    cmake --build "$build_dir" --parallel "$(nproc)" "${target_args[@]}" >&2
}
