#!/usr/bin/env bash
# Install (idempotent) and run the whole test suite: serial pytest (kernels, end-to-end
# runs through the command line on 1-4 ranks), then the MPI tests on 2 ranks (pytest-mpi).
set -euo pipefail
cd "$(dirname "$0")/.."
bash jobs/install.sh
. .venv/bin/activate
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1
ruff check pdfem partition tests
# The type hints of the modules listed in pyproject.toml ([tool.mypy])
python -m mypy
python -m pytest -q -p no:cacheprovider --durations=30 "$@"
timeout 900 bash jobs/mpirun.sh -n 2 python -m pytest -q -p no:cacheprovider --with-mpi tests/mpi
