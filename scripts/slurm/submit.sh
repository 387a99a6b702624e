#!/usr/bin/env bash
# Submits a sharded `cloud-analysis batch` run to Slurm: a job array of TASKS tasks, each with
# its share of the frame list, and a merge job that runs when all of them have ended.
# usage: scripts/slurm/submit.sh --kitti-root DIR --list FILE --out-dir DIR --tasks N
#            [--array IDS] [--cpus C] [--mem MEM] [--time LIMIT] [--parallel P] [--exe PATH]
#            [-- batch flags]
#   --tasks N      number of shards = array size
#   --array IDS    submit only these tasks of the N (e.g. 3,7 or 2-4: tasks to redo; they
#                  resume, and the merge job merges every shard's report again)
#   --cpus C       CPUs per task (default 2: the batch keeps two cores busy)
#   --mem MEM      memory per task (default 600M: measured peak ~200-250 MB plus headroom)
#   --time LIMIT   time limit per task (default 02:00:00); size it from frames/N and the fps
#   --parallel P   at most P tasks at once (sbatch's %P); default: no limit
#   --exe PATH     cloud-analysis executable (default: the one on PATH)
# Prints "<array job id> <merge job id>". Sizing: docs/cluster.md.
set -euo pipefail

here=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)
cpus=2 mem=600M time_limit=02:00:00 parallel="" exe=cloud-analysis
kitti_root="" list="" out_dir="" tasks="" array_ids=""
extra=()
usage() { echo "submit: error: usage: $1 (see --help)" >&2; exit 2; }
while [ $# -gt 0 ]; do
    case "$1" in
        --kitti-root) kitti_root=$2; shift 2 ;;
        --list) list=$2; shift 2 ;;
        --out-dir) out_dir=$2; shift 2 ;;
        --tasks) tasks=$2; shift 2 ;;
        --cpus) cpus=$2; shift 2 ;;
        --mem) mem=$2; shift 2 ;;
        --time) time_limit=$2; shift 2 ;;
        --parallel) parallel=$2; shift 2 ;;
        --exe) exe=$2; shift 2 ;;
        --) shift; extra=("$@"); break ;;
        --array) array_ids=$2; shift 2 ;;
        -h|--help) sed -n '2,17p' "$0"; exit 0 ;;
        *) usage "unknown argument '$1'" ;;
    esac
done
[ -n "$kitti_root" ] || usage "--kitti-root is required"
[ -n "$list" ] || usage "--list is required"
[ -n "$out_dir" ] || usage "--out-dir is required"
[[ "$tasks" =~ ^[1-9][0-9]*$ ]] || usage "--tasks must be a positive integer"
abs() { (cd "$(dirname "$1")" && echo "$(pwd)/$(basename "$1")"); }
mkdir -p "$out_dir/reports" "$out_dir/logs"
kitti_root=$(abs "$kitti_root")
list=$(abs "$list")
out_dir=$(abs "$out_dir")
if [[ "$exe" == */* ]]; then exe=$(abs "$exe"); fi

array="${array_ids:-0-$((tasks - 1))}${parallel:+%$parallel}"
env="ALL,KITTI_ROOT=$kitti_root,LIST=$list,OUT_DIR=$out_dir,SHARDS=$tasks,CLOUD_ANALYSIS=$exe"
array_job=$(sbatch --parsable --array="$array" --cpus-per-task="$cpus" --mem="$mem" \
    --time="$time_limit" --export="$env" --output="$out_dir/logs/shard-%a.log" \
    "$here/batch-array.sbatch" "${extra[@]}")
array_job=${array_job%%;*}
merge_job=$(sbatch --parsable --dependency="afterany:$array_job" --export="$env" \
    --output="$out_dir/logs/merge.log" "$here/merge.sbatch")
merge_job=${merge_job%%;*}
echo "$array_job $merge_job"
