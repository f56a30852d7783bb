"""Helpers shared by the tests: the real command line as a subprocess, run-file contents."""

import os
import subprocess
import sys
from pathlib import Path

import h5py

ROOT = Path(__file__).resolve().parents[1]
MPIRUN = ["bash", str(ROOT / "jobs" / "mpirun.sh")]


def pdfem(args, cwd, ranks=None, timeout=300, env=None):
    """Run ``python -m pdfem`` (under mpirun when ranks is given; env: variables to set);
    return the process."""
    cmd = [sys.executable, "-m", "pdfem"] + list(args)
    if ranks:
        cmd = MPIRUN + ["-n", str(ranks)] + cmd
    env = dict(os.environ, PYTHONPATH=str(ROOT), **(env or {}))
    return subprocess.run(cmd, cwd=cwd, capture_output=True, text=True, timeout=timeout,
                          env=env)


def datasets(path):
    """Every dataset of an HDF5 file as {name: array}."""
    out = {}
    with h5py.File(path) as f:
        f.visititems(lambda n, o: out.__setitem__(n, o[()])
                     if isinstance(o, h5py.Dataset) else None)
    return out
