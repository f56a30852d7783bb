#!/usr/bin/env bash
# PBS Pro / Torque job: one pdfem run on several nodes that chains itself across walltime.
#   qsub -v SCENE=my.toml,RUN=runs/my.h5 jobs/pbs.sh
# PBS sends SIGTERM to the job's processes at the walltime (then SIGKILL after a grace
# period, kill_delay); the ranks write <run>.ckpt.h5 and the run ends with status 0 (mpirun
# started by jobs/mpirun.sh's pdfem_mpirun, which sees to that: read its header). The job
# resubmits itself with --restart until the run file <run> exists; any other failure ends the
# chain with mpirun's status. Submit from the project folder (jobs/, .venv).
#PBS -N pdfem
#PBS -l select=2:ncpus=32:mpiprocs=32
#PBS -l walltime=04:00:00
#PBS -j oe
set -euo pipefail
: "${SCENE:?qsub -v SCENE=...,RUN=... jobs/pbs.sh}" "${RUN:?qsub -v SCENE=...,RUN=... jobs/pbs.sh}"
cd "${PBS_O_WORKDIR:-.}"

# Site modules (edit for your cluster), then the project's environment
module load openmpi hdf5-mpi 2>/dev/null || true
. .venv/bin/activate
. jobs/mpirun.sh

RESTART=()
if [ -f "$RUN.ckpt.h5" ] && [ ! -f "$RUN" ]; then
  RESTART=(--restart "$RUN.ckpt.h5")
fi
NP=$(wc -l < "${PBS_NODEFILE:-/dev/null}" || echo 1)
# The walltime's SIGTERM: a checkpoint and status 0; a failure: its status ends the chain
pdfem_mpirun -n "${NP:-1}" python -m pdfem run "$SCENE" -o "$RUN" "${RESTART[@]}"

if [ ! -f "$RUN" ] && [ -f "$RUN.ckpt.h5" ]; then
  qsub -v "SCENE=$SCENE,RUN=$RUN" "$0"
fi
