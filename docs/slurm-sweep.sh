#!/usr/bin/env bash
# Runs one vlab sweep on a Slurm cluster as a job array, one shard per array
# task, and merges the shards in a second job that starts when every task has
# ended. Run it on the login node with bash (not sbatch); it submits itself:
#
#   bash docs/slurm-sweep.sh                       # the sweep of issue 11 (below)
#   SHARDS=16 bash docs/slurm-sweep.sh --freq 20,40 --gamma 1,3,20 --seeds 1,2,3
#
# Arguments are those of `vlab sweep` (without --shard, --out, --resume); every
# task gets the same ones. Environment:
#   SHARDS  number of array tasks (shards) [8]
#   OUT     folder of the shards and the merged sweep [sweep-shards]
#   VLAB    the vlab binary [vlab on the PATH]
#   SBATCH  the sbatch command [sbatch] (the test suite puts a stub here)
#
# Each task runs `vlab sweep ARGS --shard I/N --out OUT/shardI --resume` and
# keeps OUT/shardI/sweep.csv up to date after every condition: a task that was
# preempted or hit its time limit is rerun with
#   SHARDS=N OUT=OUT VLAB=VLAB sbatch --array=I OUT/job.sh ARGS
# (OUT/submit.log holds the line as it was submitted)
# (with the same SHARDS, OUT and VLAB) and computes only what its file lacks. The merge job runs `vlab sweep merge`
# once all tasks have ended (whether or not they succeeded): it writes
# OUT/merged/sweep.csv, equal row for row to what the unsharded sweep writes
# (only wall times differ), and the plots; it refuses shards of different
# sweeps and shards that lack conditions, naming them, so a failed task shows
# in the merge job's log (OUT/slurm-merge-JOBID.out). Rerun the task, then the
# merge by hand: vlab sweep merge OUT/shard* --out OUT/merged
#
# Resources: a thesis-scene condition run until steady takes from about 20 s
# (bouncing bed, 40 Hz) to a few minutes of one core (see docs/maps.md);
# a task runs as many conditions at a time as it has CPUs.
#SBATCH --job-name=vlab-sweep
#SBATCH --cpus-per-task=2
#SBATCH --mem-per-cpu=200M
#SBATCH --time=04:00:00
set -euo pipefail

SHARDS=${SHARDS:-8}
OUT=${OUT:-sweep-shards}
VLAB=${VLAB:-vlab}
SBATCH=${SBATCH:-sbatch}
if [[ $# -eq 0 ]]; then
    set -- --freq 20,40,80 --gamma 1,1.5,2,3,5,8,12,20,30,40 --seeds 1,2,3
fi

if [[ -z "${SLURM_ARRAY_TASK_ID:-}" ]]; then
    # On the login node: submit the array, then the merge after it.
    if ! [[ "$SHARDS" =~ ^[1-9][0-9]*$ ]]; then
        echo "SHARDS = '$SHARDS': a whole number of at least 1" >&2
        exit 2
    fi
    mkdir -p "$OUT"
    # Slurm runs a copy of the script; keep one beside the results for reruns.
    cp "$0" "$OUT/job.sh"
    export SHARDS OUT VLAB
    array=$("$SBATCH" --parsable --array="1-$SHARDS" \
        --output="$OUT/slurm-%A_%a.out" "$OUT/job.sh" "$@")
    array=${array%%;*}   # --parsable prints "jobid" or "jobid;cluster"
    shards=()
    for i in $(seq 1 "$SHARDS"); do
        shards+=("$OUT/shard$i")
    done
    merge=$(printf '%q ' "$VLAB" sweep merge "${shards[@]}" --out "$OUT/merged")
    "$SBATCH" --parsable --dependency="afterany:$array" --job-name=vlab-sweep-merge \
        --cpus-per-task=1 --time=00:10:00 \
        --output="$OUT/slurm-merge-%j.out" --wrap "$merge" >/dev/null
    {
        echo "# the array as submitted; to rerun task I, replace 1-$SHARDS by I"
        printf '%q ' "SHARDS=$SHARDS" "OUT=$OUT" "VLAB=$VLAB" "$SBATCH" \
            --array="1-$SHARDS" --output="$OUT/slurm-%A_%a.out" "$OUT/job.sh" "$@"
        echo
    } >"$OUT/submit.log"
    echo "submitted array job $array ($SHARDS shards) and its merge; results in $OUT/merged"
    exit 0
fi

# Inside the array: one shard.
I=$SLURM_ARRAY_TASK_ID
exec "$VLAB" --threads "${SLURM_CPUS_PER_TASK:-1}" sweep "$@" \
    --shard "$I/$SHARDS" --out "$OUT/shard$I" --resume
