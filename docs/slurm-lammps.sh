#!/usr/bin/env bash
# Runs a deck `vlab export lammps` wrote on a Slurm cluster with as many MPI
# ranks as the job has tasks, then puts its record through vlab's rig
# (`vlab replay`), for beds too big for one machine. Submit it with sbatch
# from the folder above the deck:
#
#   vlab export lammps --scene big.toml --freq 40 --gamma 20 --cycles 25 --steady-cycles 16 --out big-lmp
#   sbatch --ntasks=16 docs/slurm-lammps.sh big-lmp            # then: big-lmp/replay/
#   sbatch --ntasks=16 docs/slurm-lammps.sh big-lmp --rig ideal
#
# Arguments: the deck's folder, then any flags of `vlab replay` (not --out).
# Environment:
#   LMP     the LAMMPS binary [lmp]
#   VLAB    the vlab binary [vlab on the PATH]
#   LAUNCH  what starts the ranks [srun; `mpirun -np N` off Slurm]
#
# LAMMPS writes lammps.log and record.txt into the deck's folder; the replay
# writes the rig's record, the measurement and summary.json into
# DECK/replay. LAMMPS splits the bed into one domain per rank: on 2 ranks
# of the 2-core VM the 5 000-sphere bed of docs/replay-lammps.md ran 1.39
# times faster than on one (see there).
#SBATCH --job-name=vlab-lammps
#SBATCH --ntasks=2
#SBATCH --mem-per-cpu=500M
#SBATCH --time=04:00:00
set -euo pipefail

if [[ $# -lt 1 ]]; then
    echo "usage: sbatch [--ntasks=N] $0 DECK_FOLDER [vlab replay flags]" >&2
    exit 2
fi
DECK=$1
shift
LMP=${LMP:-lmp}
VLAB=${VLAB:-vlab}
LAUNCH=${LAUNCH:-srun}
if [[ ! -f "$DECK/in.damper" || ! -f "$DECK/packing.data" ]]; then
    echo "$DECK: no in.damper and packing.data; write them with vlab export lammps --out $DECK" >&2
    exit 2
fi
for arg in "$@"; do
    if [[ "$arg" == --out || "$arg" == --out=* ]]; then
        echo "--out: the replay goes to $DECK/replay" >&2
        exit 2
    fi
done

# The deck reads packing.data and writes record.txt beside itself.
(cd "$DECK" && $LAUNCH "$LMP" -in in.damper -log lammps.log)
"$VLAB" replay "$DECK/record.txt" --out "$DECK/replay" "$@"
