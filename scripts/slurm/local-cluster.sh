#!/usr/bin/env bash
# Starts a throw-away single-node Slurm on this machine (munged, slurmctld, slurmd with a
# generated munge key and slurm.conf in a temporary folder, loopback only), runs COMMAND against
# it with SLURM_CONF exported, and stops every daemon and job on exit, failure or signal.
#
# usage: scripts/slurm/local-cluster.sh [--cpus N] [--timeout SECONDS] [--dir DIR] [-- COMMAND...]
#   --cpus N       CPUs the node offers to jobs (default: nproc)
#   --timeout S    COMMAND is killed after S seconds (default 600)
#   --dir DIR      keep the cluster's files (conf, logs, state) in DIR instead of a temp folder
#   COMMAND        default: one job that prints its node name (a self-test)
# Exit: COMMAND's code; 1 when the cluster does not come up; 77 when slurm-wlm or munge is
# missing (CTest's skip code). As root with user namespaces available, everything runs in a
# private network and PID namespace: only loopback exists, and when the script ends the kernel
# ends every process it started. Otherwise the daemons listen on free loopback ports of the host
# and are stopped by pid, as are the jobs (found by a marker variable in their environment).
set -euo pipefail

cpus=$(nproc)
timeout_s=600
dir=""
command=()
while [ $# -gt 0 ]; do
    case "$1" in
        --cpus) cpus=$2; shift 2 ;;
        --timeout) timeout_s=$2; shift 2 ;;
        --dir) dir=$2; shift 2 ;;
        --) shift; command=("$@"); break ;;
        -h|--help) sed -n '2,16p' "$0"; exit 0 ;;
        *) echo "local-cluster: error: usage: unknown argument '$1' (see --help)" >&2; exit 2 ;;
    esac
done

for exe in munged mungekey slurmctld slurmd sbatch sinfo scontrol; do
    if ! command -v "$exe" >/dev/null 2>&1 && [ ! -x "/usr/sbin/$exe" ]; then
        echo "local-cluster: $exe not found: install slurm-wlm and munge (scripts/install-deps.sh)" >&2
        exit 77
    fi
done
export PATH="$PATH:/usr/sbin:/sbin"

# Re-run inside fresh network + PID namespaces when possible (--kill-child: if this script is
# killed, the namespace's first process dies and the kernel kills everything else in it).
if [ -z "${LOCAL_CLUSTER_NAMESPACED:-}" ] && [ -z "${LOCAL_CLUSTER_NO_NAMESPACE:-}" ] &&
    [ "$(id -u)" -eq 0 ] &&
    unshare --net --pid --fork --mount-proc --kill-child true 2>/dev/null; then
    export LOCAL_CLUSTER_NAMESPACED=1
    exec unshare --net --pid --fork --mount-proc --kill-child "$0" --cpus "$cpus" \
        --timeout "$timeout_s" ${dir:+--dir "$dir"} -- "${command[@]}"
fi

if [ -n "${LOCAL_CLUSTER_NAMESPACED:-}" ]; then
    # glibc's getaddrinfo(AI_ADDRCONFIG), which Slurm uses, finds no IPv4 when 127.0.0.1 is
    # the only address: a second loopback address makes it answer.
    ip link set lo up
    ip addr add 127.0.0.2/32 dev lo
    ctld_port=6817
    slurmd_port=6818
else
    free_port() { python3 -c 'import socket; s=socket.socket(); s.bind(("127.0.0.1",0)); print(s.getsockname()[1])'; }
    ctld_port=$(free_port)
    slurmd_port=$(free_port)
fi

if [ -z "$dir" ]; then
    dir=$(mktemp -d "${TMPDIR:-/tmp}/local-slurm.XXXXXX")
    remove_dir=1
else
    mkdir -p "$dir"
    remove_dir=0
fi
dir=$(cd "$dir" && pwd)
# munged wants its socket folder reachable (x) by every user, and no one else writing there.
chmod 711 "$dir"
mkdir -p "$dir/state" "$dir/spool" "$dir/munge"
chmod 711 "$dir/munge"
# Every process started from here on (daemons, job steps, jobs) carries this marker.
export LOCAL_CLUSTER_ID="$dir"
export SLURM_CONF="$dir/slurm.conf"
user=$(id -un)
mem_mb=$(awk '/^MemTotal:/ { printf "%d", $2 / 1024 * 0.9 }' /proc/meminfo)

pids=()
cleanup() {
    local code=$?
    trap - EXIT INT TERM HUP
    # Jobs first (scancel, bounded wait), then the daemons by pid, then anything left that
    # carries the marker (job steps reparented away from slurmd).
    if [ -f "$dir/slurm.conf" ]; then
        timeout 5 scancel --full --quiet --user="$user" 2>/dev/null || true
    fi
    for ((i = ${#pids[@]} - 1; i >= 0; i--)); do kill -TERM "${pids[i]}" 2>/dev/null || true; done
    for _ in $(seq 50); do
        local alive=0
        for p in "${pids[@]}"; do kill -0 "$p" 2>/dev/null && alive=1; done
        [ "$alive" = 0 ] && break
        sleep 0.1
    done
    for p in "${pids[@]}"; do kill -KILL "$p" 2>/dev/null || true; done
    local self=$$ environ
    for environ in /proc/[0-9]*/environ; do
        local p=${environ#/proc/}
        p=${p%/environ}
        [ "$p" = "$self" ] && continue
        if { tr '\0' '\n' <"$environ" | grep -qxF "LOCAL_CLUSTER_ID=$dir"; } 2>/dev/null; then
            kill -KILL "$p" 2>/dev/null || true
        fi
    done
    echo "local-cluster: stopped after $SECONDS s" >&2
    if [ "$code" -ne 0 ]; then
        for log in slurmctld slurmd munged; do
            [ -f "$dir/$log.log" ] || continue
            echo "local-cluster: last lines of $dir/$log.log:" >&2
            tail -n 15 "$dir/$log.log" >&2
        done
    fi
    [ "$remove_dir" = 1 ] && rm -rf "$dir"
    exit "$code"
}
trap cleanup EXIT
trap 'exit 130' INT
trap 'exit 143' TERM
trap 'exit 129' HUP

mungekey --create --keyfile="$dir/munge/munge.key" --bits=1024 --force 2>/dev/null
chmod 400 "$dir/munge/munge.key"
munged --foreground --force --socket="$dir/munge/munge.socket" \
    --key-file="$dir/munge/munge.key" --pid-file="$dir/munge/munged.pid" \
    --seed-file="$dir/munge/munged.seed" --log-file="$dir/munged.log" 2>>"$dir/munged.log" &
pids+=($!)

cat >"$SLURM_CONF" <<CONF
# Generated by scripts/slurm/local-cluster.sh: one node, loopback only, files in $dir.
ClusterName=local
SlurmctldHost=localhost(127.0.0.1)
SlurmctldPort=$ctld_port
SlurmdPort=$slurmd_port
AuthType=auth/munge
AuthInfo=socket=$dir/munge/munge.socket
CredType=cred/munge
SlurmUser=$user
SlurmdUser=root
StateSaveLocation=$dir/state
SlurmdSpoolDir=$dir/spool
SlurmctldPidFile=$dir/slurmctld.pid
SlurmdPidFile=$dir/slurmd.pid
SlurmctldLogFile=$dir/slurmctld.log
SlurmdLogFile=$dir/slurmd.log
SlurmctldDebug=info
SlurmdDebug=${LOCAL_CLUSTER_SLURMD_DEBUG:-info}
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
JobCompType=jobcomp/none
SwitchType=switch/none
MpiDefault=none
SchedulerType=sched/builtin
SelectType=select/cons_tres
SelectTypeParameters=CR_Core_Memory
ReturnToService=2
SlurmdParameters=config_overrides
KillWait=2
MinJobAge=300
InactiveLimit=0
SlurmctldTimeout=30
SlurmdTimeout=30
MessageTimeout=10
NodeName=localnode NodeHostname=$(hostname -s) NodeAddr=127.0.0.1 CPUs=$cpus RealMemory=$mem_mb State=UNKNOWN
PartitionName=local Nodes=localnode Default=YES MaxTime=INFINITE State=UP
CONF

for _ in $(seq 50); do [ -S "$dir/munge/munge.socket" ] && break; sleep 0.1; done
slurmctld -D -i -f "$SLURM_CONF" >>"$dir/slurmctld.log" 2>&1 &
pids+=($!)
slurmd -D -N localnode -f "$SLURM_CONF" >>"$dir/slurmd.log" 2>&1 &
pids+=($!)

ready=0
deadline=$((SECONDS + 30))
while [ "$SECONDS" -lt "$deadline" ]; do
    state=$(timeout 3 sinfo -h -N -n localnode -o %t 2>/dev/null || true)
    if [ "$state" = idle ]; then
        ready=1
        break
    fi
    sleep 0.1
done
if [ "$ready" = 0 ]; then
    echo "local-cluster: error: the node did not become idle within 30 s (state '${state:-none}')" >&2
    exit 1
fi

echo "local-cluster: up in $SECONDS s (files in $dir)" >&2
if [ ${#command[@]} -eq 0 ]; then
    command=(bash -c 'out=$(sbatch --wait --quiet --output=/dev/stdout --wrap "srun hostname") && echo "local-cluster: a job ran: $out"')
fi
set +e
timeout --kill-after=5 "$timeout_s" "${command[@]}"
code=$?
set -e
[ "$code" = 124 ] && echo "local-cluster: error: command timed out after $timeout_s s" >&2
exit "$code"
