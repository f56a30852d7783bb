#!/usr/bin/env bash
# Install pdfem on a fresh Debian machine: Open MPI, parallel HDF5, a venv with
# h5py built against parallel HDF5, and the project itself (editable).
# Idempotent: each step is skipped when its result is already there.
set -euo pipefail
cd "$(dirname "$0")/.."
VENV=${PDFEM_VENV:-.venv}

# System packages (Open MPI and parallel HDF5), only when missing
need=""
for p in openmpi-bin libopenmpi-dev libhdf5-openmpi-dev pkg-config gcc; do
  dpkg -s "$p" >/dev/null 2>&1 || need="$need $p"
done
if [ -n "$need" ]; then
  SUDO=""; [ "$(id -u)" -eq 0 ] || SUDO="sudo"
  $SUDO apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq $need >/dev/null
fi

# Virtual environment with the Python dependencies
[ -x "$VENV/bin/python" ] || python3 -m venv "$VENV"
. "$VENV/bin/activate"
python -m pip install -q --upgrade pip >/dev/null
python -m pip install -q mpi4py numpy numba meshio pytest pytest-mpi hypothesis \
  matplotlib ruff mypy "setuptools>=77" "cython>=3" pkgconfig wheel

# h5py against parallel HDF5 (no build isolation: see docs/user/running.md, Install)
if ! python -c "import h5py, sys; sys.exit(0 if h5py.get_config().mpi else 1)" 2>/dev/null; then
  CC=mpicc HDF5_MPI=ON HDF5_PKGCONFIG_NAME=hdf5-openmpi \
    python -m pip install -q --no-binary=h5py --no-build-isolation --force-reinstall --no-deps h5py
fi

# The project itself
python -m pip install -q --no-build-isolation --no-deps -e .
echo "pdfem installed in $VENV"
