#!/usr/bin/env bash
# Install (idempotent) and run the default scene on 2 ranks: mpirun -n 2 python -m pdfem
set -euo pipefail
cd "$(dirname "$0")/.."
bash jobs/install.sh
. .venv/bin/activate
bash jobs/mpirun.sh -n "${PDFEM_RANKS:-2}" python -m pdfem "$@"
