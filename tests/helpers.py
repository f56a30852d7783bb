"""Helpers shared by the tests: the real command line as a subprocess, run-file contents."""

import os
import subprocess
import sys
from pathlib import Path

import h5py
import numpy as np

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


def same_bits_on_one_and_two_ranks(scene, cwd):
    """Run the scene file ``scene`` (in ``cwd``) on 1 and on 2 ranks, to one.h5 and two.h5;
    assert that both end well with every dataset identical; return the datasets."""
    one = pdfem(["run", scene, "-o", "one.h5", "--quiet"], cwd)
    assert one.returncode == 0, one.stderr
    two = pdfem(["run", scene, "-o", "two.h5", "--quiet"], cwd, ranks=2)
    assert two.returncode == 0, two.stderr
    a, b = datasets(Path(cwd) / "one.h5"), datasets(Path(cwd) / "two.h5")
    assert a.keys() == b.keys()
    for k in a:
        assert np.array_equal(a[k], b[k]), k
    return a


def datasets(path):
    """Every dataset of an HDF5 file as {name: array}."""
    out = {}
    with h5py.File(path) as f:
        f.visititems(lambda n, o: out.__setitem__(n, o[()])
                     if isinstance(o, h5py.Dataset) else None)
    return out


def same_results(path_a, path_b):
    """Assert that two run files hold the same datasets, bit for bit, but for the resolved
    scene (runs of scenes that differ in a key that must not change a result); return the
    first file's datasets."""
    a, b = datasets(path_a), datasets(path_b)
    assert a.keys() == b.keys()
    for k in a:
        if k != "scene":
            assert np.array_equal(a[k], b[k]), k
    return a


def sigterm_when(args, cwd, part):
    """Run ``python -m pdfem args`` in ``cwd`` (1 process), send it SIGTERM 0.2 s after the
    file ``part`` appears (within 120 s), and return (exit status, stdout, stderr)."""
    import signal
    import time

    env = dict(os.environ, PYTHONPATH=str(ROOT))
    proc = subprocess.Popen([sys.executable, "-m", "pdfem", *args], cwd=cwd, env=env,
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    t0 = time.time()
    while not part.exists():
        assert time.time() - t0 < 120 and proc.poll() is None
        time.sleep(0.01)
    time.sleep(0.2)
    proc.send_signal(signal.SIGTERM)
    out, err = proc.communicate(timeout=120)
    return proc.returncode, out, err
