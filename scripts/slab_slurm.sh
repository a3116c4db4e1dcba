#!/usr/bin/env bash
# Example Slurm job array for a large slab run: one shard per array task, each resuming from
# its own checkpoint if the task is requeued; then one merge. The shards' tables are the same
# bits as a single-process run of the same config and seed.
#
#   sbatch --array=1-8 scripts/slab_slurm.sh                     # 8 shards of the default tables
#   nephele merge --config fit-configs/slab-default.json --out outputs/slab shards/*
#
# scripts/slurm_local.sh runs it under a real one-node Slurm (CI does) and checks the merged
# tables against one process; docs/integration.md says how it scales to a cluster.
#
#SBATCH --job-name=nephele-slab
#SBATCH --cpus-per-task=8
#SBATCH --time=04:00:00
#SBATCH --requeue
set -euo pipefail
CFG=${CFG:-fit-configs/slab-default.json}
K=${SLURM_ARRAY_TASK_ID:?run this as a Slurm array job (sbatch --array=1-N)}
N=${SLURM_ARRAY_TASK_COUNT:-${SHARDS:?set SHARDS=N when Slurm does not export SLURM_ARRAY_TASK_COUNT}}
export RAYON_NUM_THREADS=${SLURM_CPUS_PER_TASK:-1}
exec "${NEPHELE:-nephele}" slab --config "$CFG" --out "shards/$K" --shard "$K/$N" --no-plot
