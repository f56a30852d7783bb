#!/usr/bin/env bash
# Install (idempotent) and run the default scene on 2 ranks: mpirun -n 2 python -m pdfem.
# With no arguments it runs `pdfem run --force`, so a second call replaces the run file of
# the first instead of stopping at it; arguments are passed to pdfem as given.
set -euo pipefail
cd "$(dirname "$0")/.."
bash jobs/install.sh
. .venv/bin/activate
if [ $# -eq 0 ]; then
  set -- run --force
fi
bash jobs/mpirun.sh -n "${PDFEM_RANKS:-2}" python -m pdfem "$@"
