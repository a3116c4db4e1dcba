#!/usr/bin/env bash
# A real Slurm run of the sharded slab tables on one machine.
#
# Sets up a single-node cluster on localhost (munge, slurmctld and slurmd from Debian's
# slurm-wlm, a slurm.conf written here), submits scripts/slab_slurm.sh as a job array of
# SHARDS tasks on a small config, merges the shards with `nephele merge`, runs the same config
# in one process, and checks that the two tables.npz are the same bytes. Prints the seconds of
# each step. Needs root (it installs the packages if they are missing and starts the daemons)
# and a built nephele (target/release/nephele).
#
#   scripts/slurm_local.sh [SHARDS]          # default 3 shards, slab-quick at 640 000 photons
#
# On a real cluster only scripts/slab_slurm.sh and the merge are needed:
#   sbatch --array=1-N --partition=P --cpus-per-task=C --export=ALL,CFG=cfg.json \
#          --chdir=/shared/run scripts/slab_slurm.sh
#   nephele merge --config cfg.json --out outputs/slab shards/*
# - N shards split the (thickness, μ_L) slices (72 for the default tables; N beyond that
#   only adds empty shards). Each task writes shards/K (its checkpoint, resumed if the task
#   is requeued), so --chdir must be on a file system every node sees.
# - --cpus-per-task sets the threads of each task (RAYON_NUM_THREADS); the tables are the
#   same bits whatever N and C.
# - The merge reads every shard and refuses to write anything if one is missing
#   ("… in no shard"), so a failed task shows before any table does.
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."
repo=$PWD
shards=${1:-3}
nephele=$repo/target/release/nephele
[[ -x $nephele ]] || { echo "build first: cargo build --release" >&2; exit 1; }
[[ $(id -u) == 0 ]] || { echo "scripts/slurm_local.sh needs root (packages, daemons)" >&2; exit 1; }
t0=$(date +%s)
step() { echo "[$(( $(date +%s) - t0 )) s] $*"; }

if ! command -v slurmctld >/dev/null || ! command -v munged >/dev/null; then
    step "installing slurm-wlm and munge"
    apt-get update -qq >/dev/null
    DEBIAN_FRONTEND=noninteractive apt-get install -y -qq slurm-wlm munge >/dev/null
fi

work=$(mktemp -d /tmp/nephele-slurm.XXXXXX)
host=$(hostname -s)
cpus=$(nproc)
mem=$(( $(awk '/MemTotal/ {print $2}' /proc/meminfo) / 1024 - 512 ))
state=$work/state
mkdir -p "$state/spool" "$state/ctld" /run/munge /var/log/munge /var/lib/munge /etc/munge

cleanup() {
    scancel --quiet --user=root 2>/dev/null || true
    scontrol shutdown 2>/dev/null || true
    for _ in $(seq 10); do
        pgrep -x slurmctld >/dev/null || pgrep -x slurmd >/dev/null || break
        sleep 0.5
    done
    pkill -9 -x slurmd 2>/dev/null || true
    pkill -9 -x slurmctld 2>/dev/null || true
    [[ -n ${munge_pid:-} ]] && kill "$munge_pid" 2>/dev/null || true
    rm -rf "$work"
}
trap cleanup EXIT

step "munge"
if [[ ! -s /etc/munge/munge.key ]]; then
    dd if=/dev/urandom of=/etc/munge/munge.key bs=1024 count=1 status=none
fi
chown -R munge:munge /etc/munge /run/munge /var/log/munge /var/lib/munge 2>/dev/null || true
chmod 0400 /etc/munge/munge.key
if ! munge -n >/dev/null 2>&1; then
    sudo_munge() { if id munge >/dev/null 2>&1; then runuser -u munge -- "$@"; else "$@"; fi; }
    sudo_munge munged --force
    munge_pid=$(pgrep -x munged | head -1)
fi
munge -n | unmunge >/dev/null

step "slurm.conf for one node: $host, $cpus CPUs, $mem MB"
conf=$work/slurm.conf
cat > "$conf" <<EOF
ClusterName=nephele-local
SlurmctldHost=$host
SlurmUser=root
SlurmdUser=root
AuthType=auth/munge
StateSaveLocation=$state/ctld
SlurmdSpoolDir=$state/spool
SlurmctldPidFile=$state/slurmctld.pid
SlurmdPidFile=$state/slurmd.pid
SlurmctldLogFile=$work/slurmctld.log
SlurmdLogFile=$work/slurmd.log
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
SelectType=select/cons_tres
SelectTypeParameters=CR_CPU
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
MpiDefault=none
ReturnToService=2
SchedulerType=sched/backfill
NodeName=$host CPUs=$cpus RealMemory=$mem State=UNKNOWN
PartitionName=local Nodes=$host Default=YES MaxTime=INFINITE State=UP
EOF
export SLURM_CONF=$conf
slurmctld -f "$conf"
slurmd -f "$conf"
for _ in $(seq 60); do
    if sinfo -h -o '%T' 2>/dev/null | grep -q -E '^(idle|mixed|allocated)'; then break; fi
    sleep 1
done
sinfo -h -o '%T' | grep -q -E '^(idle|mixed|allocated)' || {
    echo "the node never came up:" >&2
    tail -20 "$work/slurmctld.log" "$work/slurmd.log" >&2
    exit 1
}
step "cluster up: $(sinfo -h -o '%P %D node(s) %T')"

cfg=$work/slab.json
python3 - "$repo/fit-configs/slab-quick.json" "$cfg" <<'PY'
import json, sys
c = json.load(open(sys.argv[1]))
c["stop"]["max_photons"] = 640000
c["stop"]["target_rel_se"] = 0.0
json.dump(c, open(sys.argv[2], "w"))
PY

step "sbatch --array=1-$shards scripts/slab_slurm.sh"
mkdir -p "$work/run"
sbatch --wait --array="1-$shards" --cpus-per-task=1 --time=00:10:00 \
    --chdir="$work/run" --output="$work/run/task-%a.log" \
    --export="ALL,CFG=$cfg,NEPHELE=$nephele,SHARDS=$shards" \
    "$repo/scripts/slab_slurm.sh" || {
    echo "the job array failed:" >&2
    tail -n 20 "$work"/run/task-*.log >&2
    exit 1
}
for k in $(seq "$shards"); do
    [[ -d $work/run/shards/$k ]] || { echo "task $k left no shard" >&2; exit 1; }
done
for k in $(seq "$shards"); do
    step "task $k: $(grep -m1 -o 'shard [0-9]*/[0-9]*.*' "$work/run/task-$k.log" | cut -c1-60 || echo 'ran')"
done
step "array done; merging"
"$nephele" merge --config "$cfg" --out "$work/merged" --no-plot "$work"/run/shards/* >/dev/null

step "the same config in one process"
"$nephele" slab --config "$cfg" --out "$work/single" --no-plot >/dev/null

if cmp -s "$work/merged/tables.npz" "$work/single/tables.npz"; then
    step "OK: $shards Slurm array tasks merged = one process, tables.npz byte for byte ($(stat -c %s "$work/single/tables.npz") bytes)"
else
    echo "merged Slurm shards differ from the single-process tables" >&2
    exit 1
fi
