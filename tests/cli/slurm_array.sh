#!/usr/bin/env bash
# The cluster path on a real Slurm (run inside scripts/slurm/local-cluster.sh): a 3-task array
# over the bundled rendered frames, one task killed (SIGKILL) after its first frame and
# resubmitted, the merge job after each; every entity file must be byte-identical to a plain
# one-process batch, and the resubmitted task must not have rewritten a finished frame.
# usage: slurm_array.sh CLOUD_ANALYSIS_EXE SAMPLES_DIR SCRIPTS_SLURM_DIR WORK_DIR
set -euo pipefail

exe=$1 samples=$2 slurm_dir=$3 work=$4
rm -rf "$work"
mkdir -p "$work"
step() { echo "slurm_array: [${SECONDS} s] $*" >&2; }
fail() { echo "slurm_array: FAIL: $*" >&2; exit 1; }
# wait_for SECONDS DESCRIPTION COMMAND...: polls COMMAND every 0.1 s until it succeeds.
wait_for() {
    local limit=$1 what=$2
    shift 2
    local deadline=$((SECONDS + limit))
    until "$@"; do
        [ "$SECONDS" -lt "$deadline" ] || fail "timed out after $limit s waiting for $what"
        sleep 0.1
    done
}
no_jobs() { [ -z "$(squeue -h -o %i 2>/dev/null)" ]; }
log_dump() { tail -n 5 "$work"/out/logs/*.log >&2 2>/dev/null || true; }
trap 'code=$?; [ "$code" = 0 ] || log_dump' EXIT

# A KITTI-layout root of 30 frames: the three rendered scenes, ten times each (links). Ten
# frames a task leave time to kill task 1 after its first frame, however loaded the machine.
shards=3
frames=30
root="$work/kitti"
mkdir -p "$root"/{image_2,image_3,semantic_rgb,disp_occ_0,calib}
scenes=(street parking-row thesis-one-car)
: >"$work/list"
for i in $(seq 0 $((frames - 1))); do
    frame=$(printf '%06d' "$i")
    scene="$samples/rendered/${scenes[i % 3]}"
    for d in image_2 image_3 semantic_rgb disp_occ_0; do ln -s "$scene/$d/000000.png" "$root/$d/$frame.png"; done
    ln -s "$scene/calib/calib_cam_to_cam.txt" "$root/calib/$frame.txt"
    echo "$frame" >>"$work/list"
done
settings=(--preset fast --evaluate)

step "plain run"
# The reference: one process, the whole list.
mkdir -p "$work/plain"
"$exe" batch --kitti-root "$root" --list "$work/list" --out-dir "$work/plain" --quiet \
    "${settings[@]}"

step "array submitted"
# The array and its merge job; task 1 is killed once its first frame is written.
out="$work/out"
read -r array_job merge_job < <("$slurm_dir/submit.sh" --kitti-root "$root" --list "$work/list" \
    --out-dir "$out" --tasks "$shards" --cpus 1 --mem 400M --time 5 --exe "$exe" -- \
    "${settings[@]}" --progress-every 1)
first_frame_of_shard_1() { [ -f "$out/000001.json" ]; }
wait_for 60 "task 1's first frame" first_frame_of_shard_1
scancel --full --signal=KILL "${array_job}_1"
step "task 1 killed"
wait_for 60 "the array and its merge job to end" no_jobs

[ -f "$out/000001.json" ] || fail "task 1's first frame is missing"
[ ! -f "$out/reports/shard-1-of-3.json" ] || fail "task 1 finished before it was killed"
grep -q "shard 1/3: no report" "$out/logs/merge.log" || fail "the first merge did not miss shard 1"
done_before=()
task1_frames=0
for i in $(seq 1 "$shards" $((frames - 1))); do
    frame=$(printf '%06d' "$i")
    task1_frames=$((task1_frames + 1))
    [ -f "$out/$frame.json" ] && done_before+=("$frame")
done
[ ${#done_before[@]} -lt "$task1_frames" ] || fail "task 1 did every frame before it was killed"
declare -A stamp
for frame in "${done_before[@]}"; do stamp[$frame]=$(stat -c '%i %.9Y' "$out/$frame.json"); done

step "array and merge ended"
# Resubmit task 1 alone (same 3 shards) with its merge job.
read -r array_job merge_job < <("$slurm_dir/submit.sh" --kitti-root "$root" --list "$work/list" \
    --out-dir "$out" --tasks "$shards" --array 1 --cpus 1 --mem 400M --time 5 --exe "$exe" -- \
    "${settings[@]}" --progress-every 1)
wait_for 60 "the resubmitted task and the merge job to end" no_jobs

step "resubmitted task and merge ended"
# Every entity file byte-identical to the one-process run; nothing else left behind.
for i in $(seq 0 $((frames - 1))); do
    frame=$(printf '%06d' "$i")
    cmp -s "$work/plain/$frame.json" "$out/$frame.json" || fail "$frame.json differs or is missing"
done
leftovers=$(find "$out" -maxdepth 1 -name '.*tmp-*' | wc -l)
[ "$leftovers" = 0 ] || fail "$leftovers temporary files left in $out"
for frame in "${done_before[@]}"; do
    [ "$(stat -c '%i %.9Y' "$out/$frame.json")" = "${stamp[$frame]}" ] ||
        fail "--resume rewrote $frame.json, finished before the kill"
done
python3 - "$out/report.json" "${#done_before[@]}" "$frames" <<'PY' || fail "merged report: see above"
import json, sys
r = json.load(open(sys.argv[1]))
skipped, frames = int(sys.argv[2]), int(sys.argv[3])
want = {"shards": 3, "shards_reported": 3, "frames": frames, "failed": 0, "skipped": skipped,
        "done": frames - skipped, "missing_shards": []}
bad = {k: (r.get(k), v) for k, v in want.items() if r.get(k) != v}
# Every frame the reporting runs analysed is scored against disp_occ_0 (not the resumed ones).
if r.get("evaluation", {}).get("frames") != frames - skipped or not 0 < r["evaluation"]["d1_all"] < 1:
    bad["evaluation"] = (r.get("evaluation"), "frames done, D1-all in (0, 1)")
if bad or not r["fps"] > 0 or not r["cpu_seconds"] > 0:
    print("slurm_array: report fields (got, want):", bad, file=sys.stderr)
    sys.exit(1)
PY
grep -q "frames, .* fps" "$out/logs/shard-0.log" || fail "no progress line in task 0's log"
echo "slurm_array: ok: $frames frames over 3 tasks, task 1 killed after ${#done_before[@]} frame(s) and resumed"
