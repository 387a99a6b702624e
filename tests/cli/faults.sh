#!/usr/bin/env bash
# The world failing around a good input (docs/reliability.md "Faults"): cloud-analysis batch
# and scene-render sensors killed with SIGKILL at random moments then resumed, two batches writing into one folder,
# a resume over truncated and foreign files, and a disk filling up mid-batch. Every finished
# run must leave byte for byte what an uninterrupted run leaves.
# usage: faults.sh CLOUD_ANALYSIS SAMPLE_DIR kill [KILLS] | lock | truncated | full-disk
#        faults.sh SCENE_RENDER DRIVE_SCENE sensors-kill [KILLS]
#   SAMPLE_DIR: samples/synthetic (left.png right.png semantic.png calib.yaml)
#   full-disk needs to mount a tmpfs (root); without it the test is skipped (exit 77)
set -euo pipefail
tool=$1 sample=$2 mode=$3
kills=${4:-20}
d=$(mktemp -d)
cleanup() {
    mountpoint -q "$d/small" 2>/dev/null && umount "$d/small"
    rm -rf "$d"
}
trap cleanup EXIT
fail() { echo "faults.sh $mode: $*" >&2; exit 1; }
kill_at() {  # MS COMMAND...: runs the command, SIGKILLed MS milliseconds after its start
    local ms=$1
    shift
    { timeout -s KILL "$(printf '%d.%03d' $((ms / 1000)) $((ms % 1000)))" "$@" \
        >/dev/null 2>&1 || true; } 2>/dev/null
}

if [ "$mode" = sensors-kill ]; then
    # scene-render sensors --frames killed at random moments, then --resume: the same files as
    # an uninterrupted render. Here `tool` is scene-render and `sample` a drive's scene file.
    n=8
    "$tool" sensors "$sample" --out "$d/reference" --frames $n >/dev/null 2>&1
    start=$(date +%s%N)
    "$tool" sensors "$sample" --out "$d/timed" --frames $n >/dev/null 2>&1
    span_ms=$((($(date +%s%N) - start) / 1000000))
    for k in $(seq 1 "$kills"); do
        out="$d/killed-$k"
        at_ms=$((RANDOM % (span_ms + 1)))
        kill_at "$at_ms" "$tool" sensors "$sample" --out "$out" --frames $n
        "$tool" sensors "$sample" --out "$out" --frames $n --resume >/dev/null 2>&1 ||
            fail "the resumed render after a kill at ${at_ms} ms failed"
        diff -r "$d/reference" "$out" >/dev/null ||
            fail "kill at ${at_ms} ms: $(diff -rq "$d/reference" "$out" | head -3)"
        rm -rf "$out"
    done
    # A complete drive resumed is left as it is: no frame rendered again.
    touch "$d/marker"
    sleep 1
    "$tool" sensors "$sample" --out "$d/reference" --frames $n --resume >/dev/null 2>&1
    [ -z "$(find "$d/reference" -type f -newer "$d/marker" ! -name sequence.json)" ] ||
        fail "--resume rendered complete frames again"
    echo "faults.sh sensors-kill: $kills kills within ${span_ms} ms, every render resumed to the reference"
    exit 0
fi

# A 30-frame list of copies of the sample (distinct ids), and the uninterrupted run.
frames=30
for i in $(seq -w 1 $frames); do
    cp "$sample/left.png" "$d/l$i.png"
    cp "$sample/right.png" "$d/r$i.png"
    cp "$sample/semantic.png" "$d/s$i.png"
    echo "l$i.png r$i.png s$i.png"
done > "$d/pairs.txt"
run() {  # out-dir [flags]: the batch of every output kind
    local out=$1
    shift
    "$tool" batch --pairs "$d/pairs.txt" --calib "$sample/calib.yaml" --out-dir "$out" \
        --clouds ply xyz --disparity-kitti --quiet "$@"
}
mkdir "$d/reference"
run "$d/reference"
same_as_reference() {  # out-dir: the same files, byte for byte, and nothing else
    diff -r "$d/reference" "$1" >/dev/null || fail "$1 differs from an uninterrupted run: $(diff -rq "$d/reference" "$1" | head -3)"
}

case "$mode" in
kill)
    # The uninterrupted run's time, and SIGKILL at random moments within it.
    start=$(date +%s%N)
    mkdir "$d/timed"
    run "$d/timed"
    span_ms=$((($(date +%s%N) - start) / 1000000))
    for k in $(seq 1 "$kills"); do
        out="$d/killed-$k"
        mkdir "$out"
        at_ms=$((RANDOM % (span_ms + 1)))
        kill_at "$at_ms" "$tool" batch --pairs "$d/pairs.txt" --calib "$sample/calib.yaml" \
            --out-dir "$out" --clouds ply xyz --disparity-kitti --quiet
        # No partial file under a final name: every entity file there is whole.
        for f in "$out"/*.json; do
            [ -e "$f" ] || continue
            cmp -s "$f" "$d/reference/$(basename "$f")" || fail "kill at ${at_ms} ms: $(basename "$f") is not whole"
        done
        run "$out" --resume
        same_as_reference "$out"
        rm -rf "$out"
    done
    echo "faults.sh kill: $kills kills within ${span_ms} ms, every run resumed to the reference"
    ;;
lock)
    # A second batch on a folder a first one holds is refused at once, writing nothing; a lock
    # file left by a dead writer is taken over.
    mkdir "$d/out"
    flock -o "$d/out/.batch.lock" sleep 30 &
    holder=$!
    for _ in $(seq 1 100); do  # until the holder has it
        flock -n "$d/out/.batch.lock" true 2>/dev/null || break
        sleep 0.1
    done
    code=0
    run "$d/out" 2>"$d/err" || code=$?
    [ "$code" = 1 ] || fail "a second writer exited $code, not 1"
    [ "$(wc -l <"$d/err")" = 1 ] || fail "not one error line: $(cat "$d/err")"
    grep -q "lock is held by another writer" "$d/err" || fail "unclear error: $(cat "$d/err")"
    grep -q ".batch.lock" "$d/err" || fail "the error does not name the lock file"
    [ -z "$(ls "$d/out")" ] || fail "the refused run wrote $(ls "$d/out" | head -3)"
    kill "$holder"
    wait "$holder" 2>/dev/null || true
    touch "$d/out/.batch.lock"  # as a killed writer leaves it
    run "$d/out"
    [ ! -e "$d/out/.batch.lock" ] || fail "the lock file outlived the batch"
    same_as_reference "$d/out"
    # Shards of one list take a lock each and run side by side.
    mkdir "$d/shards"
    run "$d/shards" --shard 0/2 &
    first=$!
    run "$d/shards" --shard 1/2
    wait "$first"
    same_as_reference "$d/shards"
    echo "faults.sh lock: a second writer refused, a stale lock taken over, two shards side by side"
    ;;
truncated)
    # A resume of a complete folder does nothing and succeeds.
    mkdir "$d/out"
    cp -r "$d/reference/." "$d/out/"
    run "$d/out" --resume
    same_as_reference "$d/out"
    # A resume over files cut short by a crash, and over a foreign file under a final name.
    head -c 100 "$d/reference/l05.json" >"$d/out/l05.json"
    head -c 1000 "$d/reference/l07.ply" >"$d/out/l07.ply"
    head -c 500 "$d/reference/l09_disparity.png" >"$d/out/l09_disparity.png"
    echo '{"not": "an entity file"}' >"$d/out/l11.json"
    printf 'garbage' >"$d/out/l13.xyz"
    run "$d/out" --resume
    same_as_reference "$d/out"
    echo "faults.sh truncated: truncated and foreign files redone by --resume"
    ;;
full-disk)
    mkdir "$d/small"
    # Room for a few frames: the sample's outputs take about 5.4 MB a frame.
    if ! mount -t tmpfs -o size=24m tmpfs "$d/small" 2>/dev/null; then
        echo "faults.sh full-disk: cannot mount a tmpfs here (not root): skipped" >&2
        exit 77
    fi
    code=0
    run "$d/small" 2>"$d/err" || code=$?
    [ "$code" = 1 ] || fail "a batch on a full disk exited $code, not 1"
    grep -q "No space left on device" "$d/err" || fail "no disk-full error: $(head -3 "$d/err")"
    grep -q "$d/small" "$d/err" || fail "the error does not name the folder"
    # Frames finished before the disk filled are whole; nothing half-written is left.
    done_frames=0
    for f in "$d/small"/*.json; do
        [ -e "$f" ] || continue
        cmp -s "$f" "$d/reference/$(basename "$f")" || fail "$(basename "$f") is not whole"
        done_frames=$((done_frames + 1))
    done
    [ "$done_frames" -ge 1 ] || fail "no frame finished before the disk filled"
    [ "$done_frames" -lt "$frames" ] || fail "the disk never filled"
    ! ls -a "$d/small" | grep -q '\.tmp-' || fail "temporary files left: $(ls -a "$d/small" | grep '\.tmp-' | head -3)"
    # Space freed: the resumed batch completes to the reference.
    mount -o remount,size=256m "$d/small"
    run "$d/small" --resume
    same_as_reference "$d/small"
    echo "faults.sh full-disk: $done_frames frames whole when the disk filled, the rest resumed"
    ;;
*)
    echo "faults.sh: unknown mode $mode" >&2
    exit 2
    ;;
esac
