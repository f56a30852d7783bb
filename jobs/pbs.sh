#!/usr/bin/env bash
# PBS Pro / Torque job: one pdfem run on several nodes that chains itself across walltime.
#   qsub -v SCENE=my.toml,RUN=runs/my.h5 jobs/pbs.sh
# PBS sends SIGTERM to the job's processes at the walltime (then SIGKILL after a grace
# period, kill_delay); mpirun forwards it to the ranks, pdfem writes <run>.ckpt.h5 and exits
# 0. Open MPI's mpirun itself then exits 1: this script counts a checkpoint written after the
# signal as the clean stop it is. The job resubmits itself with --restart until the run file
# <run> exists; any other failure ends the chain with mpirun's status.
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

RESTART=()
if [ -f "$RUN.ckpt.h5" ] && [ ! -f "$RUN" ]; then
  RESTART=(--restart "$RUN.ckpt.h5")
fi
NP=$(wc -l < "${PBS_NODEFILE:-/dev/null}" || echo 1)
# The run in the background, so that the signal's time is taken when it arrives
termed=""
trap 'termed=$(date +%s)' TERM
mpirun -n "${NP:-1}" python -m pdfem run "$SCENE" -o "$RUN" "${RESTART[@]}" & pid=$!
rc=0
wait "$pid" || rc=$?
if [ -n "$termed" ]; then
  rc=0
  wait "$pid" || rc=$?
  # mpirun's 1 after the walltime signal: a clean stop when the ranks checkpointed after it
  if [ "$rc" -eq 1 ] && [ -f "$RUN.ckpt.h5" ] \
      && [ "$(stat -c %Y "$RUN.ckpt.h5")" -ge "$termed" ]; then
    rc=0
  fi
fi
[ "$rc" -eq 0 ] || exit "$rc"

if [ ! -f "$RUN" ] && [ -f "$RUN.ckpt.h5" ]; then
  qsub -v "SCENE=$SCENE,RUN=$RUN" "$0"
fi
