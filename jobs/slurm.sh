#!/usr/bin/env bash
# Slurm job: one pdfem run on several nodes that chains itself across time limits.
#   sbatch jobs/slurm.sh my.toml runs/my.h5
# Slurm sends SIGTERM to every task at the time limit (--signal asks for it 120 s early);
# pdfem then writes <run>.ckpt.h5 and exits 0. This script resubmits itself with --restart
# until the run file <run> exists (it is renamed from <run>.part only when complete).
#SBATCH --job-name=pdfem
#SBATCH --nodes=2
#SBATCH --ntasks-per-node=32
#SBATCH --time=04:00:00
#SBATCH --signal=TERM@120
#SBATCH --output=pdfem-%j.log
set -euo pipefail
SCENE=${1:?usage: sbatch jobs/slurm.sh scene.toml run.h5}
RUN=${2:?usage: sbatch jobs/slurm.sh scene.toml run.h5}
cd "${SLURM_SUBMIT_DIR:-.}"

# Site modules: an MPI and a parallel HDF5 matching the ones h5py was built against
# (edit for your cluster), then the project's environment
module load openmpi hdf5-mpi 2>/dev/null || true
. .venv/bin/activate

# Continue from the checkpoint when an earlier job of this chain left one
RESTART=()
if [ -f "$RUN.ckpt.h5" ] && [ ! -f "$RUN" ]; then
  RESTART=(--restart "$RUN.ckpt.h5")
fi
srun python -m pdfem run "$SCENE" -o "$RUN" "${RESTART[@]}"

# Not finished (stopped at the time limit): queue the next link of the chain
if [ ! -f "$RUN" ] && [ -f "$RUN.ckpt.h5" ]; then
  sbatch "$0" "$SCENE" "$RUN"
fi
