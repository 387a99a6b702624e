#!/usr/bin/env bash
# Builds the libFuzzer harnesses (tests/fuzz, clang with ASan + UBSan, in build-fuzz/) and runs
# each in turn, seeded from the samples, assets and the bad-input corpus. A crash is copied to
# tests/corpus/fuzz/<harness>/ as a regression case; the totals are appended to
# build-fuzz/fuzz-totals.txt.
# usage: scripts/fuzz.sh [--runs N] [seconds per harness (default 60)] [harness name...]
#   --runs N   also stop a harness after N executions (whichever comes first)
# Runs at nice 19, one job at a time (the machine is shared); an input gets 60 s before it counts
# as a hang, since a shared machine can starve a nice-19 process for seconds.
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/common.sh"

runs_limit=()
if [ "${1:-}" = --runs ]; then
    runs_limit=(-runs="$2")
    shift 2
fi
seconds=${1:-60}
shift || true
root=$STEREOSCENE_ROOT
build=$root/build-fuzz
all=(fuzz_calibration fuzz_entities fuzz_palettes fuzz_gltf fuzz_point_clouds fuzz_kitti_labels
     fuzz_frame_lists)
harnesses=("${@:-${all[@]}}")

command -v clang++ >/dev/null || {
    echo "fuzz: clang++ is missing: apt-get install clang (Debian's clang has libFuzzer)" >&2
    exit 1
}
"$root/scripts/install-deps.sh"
[ -f "$build/CMakeCache.txt" ] || generator=(-G Ninja)
CC=clang CXX=clang++ cmake -S "$root" -B "$build" "${generator[@]}" -DCMAKE_BUILD_TYPE=RelWithDebInfo \
    -DSTEREOSCENE_FUZZ=ON -DCMAKE_C_COMPILER=clang -DCMAKE_CXX_COMPILER=clang++ >&2
targets=()
for h in "${harnesses[@]}"; do targets+=(--target "$h"); done
nice -n 19 cmake --build "$build" --parallel 2 "${targets[@]}" >&2

# Seeds: files of the kinds each harness reads, from the samples, the assets and the corpus.
seeds() {
    case $1 in
        fuzz_calibration) find "$root/samples" "$root/tests" -name 'calib*' -type f ;;
        fuzz_entities) find "$root/samples" "$root/tests/corpus/cases" -name '*.json' -type f | head -50 ;;
        fuzz_palettes) find "$root/assets/palettes" "$root/assets/classes" \
            -name '*.json' -type f 2>/dev/null ;;
        fuzz_gltf) find "$root/tests/scene_viewer/data/gltf" "$root/assets/models" \
            \( -name '*.gltf' -o -name '*.glb' \) -type f -size -200k ;;
        fuzz_point_clouds) find "$root/tests" "$root/samples" \
            \( -name '*.ply' -o -name '*.pcd' -o -name '*.xyz' \) -type f -size -200k ;;
        fuzz_kitti_labels) echo "$root/tests/fuzz/seeds/kitti_label.txt" ;;
        fuzz_frame_lists) find "$root/tests/corpus/cases" -name 'list*.txt' -type f ;;
    esac
}

totals=$build/fuzz-totals.txt
echo "# $(date -u +%FT%TZ) scripts/fuzz.sh ${runs_limit[*]} $seconds ${harnesses[*]}" \
    "(load average $(cut -d' ' -f1-3 /proc/loadavg))" >> "$totals"
status=0
for h in "${harnesses[@]}"; do
    work=$build/fuzz-work/$h
    crashes=$root/tests/corpus/fuzz/$h
    mkdir -p "$work/corpus" "$work/artifacts"
    # Earlier findings were copied to $crashes when found; only this run's are counted.
    rm -f "$work/artifacts"/*
    { seeds "$h" 2>/dev/null || true; } | while read -r f; do cp -n "$f" "$work/corpus/" 2>/dev/null || true; done
    [ -d "$crashes" ] && cp -n "$crashes"/* "$work/corpus/" 2>/dev/null || true
    log=$work/log.txt
    echo "fuzz: $h for $seconds s" >&2
    set +e
    start=$SECONDS
    # malloc_context_size=2: allocation stacks of two frames (recording 30 took 12-18 % of the
    # JSON harnesses' time); a crash's own stack is still complete.
    ASAN_OPTIONS=detect_leaks=0:allocator_may_return_null=1:malloc_context_size=2 \
    UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1 \
        nice -n 19 "$build/tests/fuzz/$h" -max_total_time="$seconds" -rss_limit_mb=2048 \
        -timeout=60 -report_slow_units=60 -max_len=65536 "${runs_limit[@]}" -print_final_stats=1 \
        -artifact_prefix="$work/artifacts/" \
        "$work/corpus" > "$log" 2>&1
    rc=$?
    set -e
    runs=$(grep -o 'stat::number_of_executed_units: *[0-9]*' "$log" | grep -o '[0-9]*$' || echo 0)
    # crash-, timeout-, oom- and leak- inputs are findings; libFuzzer's slow-unit- files (an input
    # over -report_slow_units seconds, which a starved nice-19 process can hit) are not.
    found=$(find "$work/artifacts" -type f ! -name 'slow-unit-*' | wc -l)
    took=$((SECONDS - start))  # wall clock: also right for a run stopped early (--runs, SIGINT)
    echo "$h executions=$runs seconds=$took findings=$found exit=$rc" \
        "load=$(cut -d' ' -f1-3 /proc/loadavg)" | tee -a "$totals" >&2
    if [ "$found" -gt 0 ]; then
        mkdir -p "$crashes"
        find "$work/artifacts" -type f ! -name 'slow-unit-*' -exec cp {} "$crashes/" \;
        status=1
    fi
done
exit $status
