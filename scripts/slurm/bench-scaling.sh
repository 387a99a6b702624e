#!/usr/bin/env bash
# Measures a sharded batch on the single-node Slurm of local-cluster.sh: the same frames with
# 1, 2 and 4 array tasks (throughput, task start-up, overhead per task), for docs/cluster.md.
# Frames are rendered here with `scene-render sensors` (never committed): DISTINCT frames
# (the scenes of samples/rendered/scenes in turn, with different sensor-noise seeds), linked to
# FRAMES frame ids in a KITTI-layout folder.
# usage: scripts/slurm/bench-scaling.sh [WORK_DIR]   (env: FRAMES=200 DISTINCT=24 TASKS="1 2 4"
#        CPUS_PER_TASK=1 PRESET=fast; BUILD=build)
set -euo pipefail
here=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)
root_dir=$(cd "$here/../.." && pwd)
work=${1:-/tmp/stereoscene-slurm-bench}
frames=${FRAMES:-200} distinct=${DISTINCT:-24} tasks_list=${TASKS:-1 2 4}
cpus=${CPUS_PER_TASK:-1} preset=${PRESET:-fast}
build="$root_dir/${BUILD:-build}"
exe="$build/cloud_analysis/cloud-analysis"
render="$build/scene_viewer/scene-render"
mkdir -p "$work"

scenes=("$root_dir"/samples/rendered/scenes/*.json)
for ((i = 0; i < distinct; i++)); do
    out="$work/rendered/$i"
    [ -f "$out/image_2/000000.png" ] && continue
    "$render" sensors "${scenes[i % ${#scenes[@]}]}" --out "$out" --frame 000000 --seed "$i" \
        >/dev/null
done
kitti="$work/kitti"
rm -rf "$kitti" && mkdir -p "$kitti"/{image_2,image_3,semantic_rgb,calib}
: >"$work/list"
for ((i = 0; i < frames; i++)); do
    id=$(printf '%06d' "$i")
    src="$work/rendered/$((i % distinct))"
    for d in image_2 image_3 semantic_rgb; do ln -s "$src/$d/000000.png" "$kitti/$d/$id.png"; done
    ln -s "$src/calib/calib_cam_to_cam.txt" "$kitti/calib/$id.txt"
    echo "$id" >>"$work/list"
done

for tasks in $tasks_list; do
    out="$work/out-$tasks"
    rm -rf "$out"
    "$here/local-cluster.sh" --timeout 1800 -- bash -c '
        set -euo pipefail
        start=$(date +%s.%N)
        read -r array merge < <("$0"/submit.sh --kitti-root "$1" --list "$2" --out-dir "$3" \
            --tasks "$4" --cpus "$5" --exe "$6" -- --preset "$7")
        while [ -n "$(squeue -h -o %i)" ]; do sleep 0.2; done
        end=$(date +%s.%N)
        python3 - "$3/report.json" "$start" "$end" "$4" <<PY
import json, sys
r = json.load(open(sys.argv[1])); start, end, tasks = float(sys.argv[2]), float(sys.argv[3]), int(sys.argv[4])
shards = [json.load(open(f"{sys.argv[1][:-11]}/reports/shard-{i}-of-{tasks}.json")) for i in range(tasks)]
first_start = min(s["started_at"] for s in shards)
frame_s = sum(sum(f.get("analyse_ms", 0) for f in s["per_frame"]) for s in shards) / 1000
print(json.dumps({"tasks": tasks, "frames": r["frames"], "done": r["done"], "failed": r["failed"],
    "submit_to_end_s": round(end - start, 2), "submit_to_first_start_s": round(first_start - start, 2),
    "wall_s": round(r["wall_seconds"], 2), "fps": round(r["fps"], 2),
    "fps_per_task": round(r["fps_per_task"], 2), "task_s": round(r["task_seconds"], 2),
    "cpu_ms_per_frame": round(r["cpu_ms_per_frame"], 1), "peak_rss_mb": round(r["peak_rss_mb"], 1),
    "task_runtimes_s": [round(s["ended_at"] - s["started_at"], 2) for s in shards]}))
PY
    ' "$here" "$kitti" "$work/list" "$out" "$tasks" "$cpus" "$exe" "$preset" | tee -a "$work/results.jsonl"
done
