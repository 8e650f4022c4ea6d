#!/usr/bin/env bash
# Runs one vlab sweep as a Slurm job array, one shard per array task, then
# merges the shards (a second job that starts when every shard succeeded).
#
#   sbatch docs/slurm-sweep.sh            # submits the array and the merge
#
# Each task runs `vlab sweep ... --shard I/N --resume`: a task that is
# preempted or times out can be resubmitted and computes only what its
# sweep.csv lacks. `vlab sweep merge` refuses shards of different sweeps,
# missing shards and unfinished shards, and writes the sweep.csv the
# unsharded sweep would have written (row for row; only wall times differ).
#
# Edit the SWEEP line (the same for every shard), N (the array size) and the
# resources. A thesis-scene condition takes 10-40 s of one core at 20-80 Hz
# with the 8-cycle protocol; with 2 cores per task each shard runs two
# conditions at a time.
#SBATCH --job-name=vlab-sweep
#SBATCH --array=1-8
#SBATCH --cpus-per-task=2
#SBATCH --time=02:00:00
#SBATCH --output=sweep-shards/slurm-%A_%a.out
set -euo pipefail

N=8   # must equal the size of --array
SWEEP=(--freq 20,40,80 --gamma 1,1.5,2,3,5,8,12,20,30,40 --seeds 1,2,3)
VLAB=${VLAB:-vlab}   # path to the vlab binary
OUT=${OUT:-sweep-shards}

if [[ -z "${SLURM_ARRAY_TASK_ID:-}" ]]; then
    # Not inside the array: submit it, and the merge after it.
    mkdir -p "$OUT"
    array=$(sbatch --parsable "$0")
    sbatch --dependency=afterok:"$array" --job-name=vlab-sweep-merge \
        --output="$OUT/slurm-merge-%j.out" --wrap \
        "$VLAB sweep merge $(for i in $(seq 1 $N); do printf '%s ' "$OUT/shard$i"; done) --out $OUT/merged"
    echo "submitted array $array and its merge; results in $OUT/merged"
    exit 0
fi

I=$SLURM_ARRAY_TASK_ID
"$VLAB" --threads "${SLURM_CPUS_PER_TASK:-1}" sweep "${SWEEP[@]}" \
    --shard "$I/$N" --out "$OUT/shard$I" --resume
