"""Checkpoints and restarts, SIGTERM and SIGKILL, and an exception on one rank.

A run continued from a checkpoint, on the same or another number of ranks, gives a run file
equal in every dataset to the run that never stopped (a settling bed: contacts, friction
history, migration).
"""

import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import h5py
import numpy as np
import pytest

from pdfem.io.checkpoint import read_checkpoint
from tests.e2e.test_cli import MPIRUN, ROOT, datasets, pdfem
from tests.scenes import settling_bed


def _bed(tmp_path, steps, extra=""):
    text = settling_bed(n=60, cols=10, end=1.0, partition="rcb").replace(
        "safety = 0.5", f"safety = 0.5\nmax_steps = {steps}")
    text = text.replace("interval = 0.25", "interval = 2.0e-5" + extra)
    (tmp_path / "bed.toml").write_text(text)
    return "bed.toml"


def _same(a, b):
    da, db = datasets(a), datasets(b)
    assert sorted(da) == sorted(db)
    for k in da:
        assert np.array_equal(da[k], db[k]), f"{k} differs"


@pytest.fixture(scope="module")
def reference(tmp_path_factory):
    """The uninterrupted 4000-step run (1 rank)."""
    d = tmp_path_factory.mktemp("ref")
    p = pdfem(["run", _bed(d, 4000), "-o", "ref.h5", "--quiet"], d)
    assert p.returncode == 0, p.stderr
    return d / "ref.h5"


@pytest.mark.parametrize("ranks", [1, 3])
def test_restart_is_bit_identical(tmp_path, reference, ranks):
    scene = _bed(tmp_path, 4000, "\ncheckpoint_interval = 1.5e-5")
    p = pdfem(["run", scene, "-o", "a.h5", "--quiet"], tmp_path, ranks=2)
    assert p.returncode == 0, p.stderr
    _same(reference, tmp_path / "a.h5")
    # The last checkpoint (t = 3e-5) continued into a new file: the later frames and the
    # whole energy series equal the uninterrupted run's
    p = pdfem(["run", scene, "--restart", "a.h5.ckpt.h5", "-o", "b.h5", "--quiet"], tmp_path,
              ranks=ranks)
    assert p.returncode == 0, p.stderr
    ref, b = datasets(reference), datasets(tmp_path / "b.h5")
    # The new file starts with a frame at the checkpoint's time; its later frames are the
    # uninterrupted run's
    nb = b["frames/time"].shape[0] - 1
    assert nb >= 1 and b["frames/time"][0] < ref["frames/time"][-nb]
    for k in ("frames/time", "frames/x", "frames/v", "frames/stress"):
        assert np.array_equal(ref[k][-nb:], b[k][1:]), k
    for k in ref:
        if k.startswith("energy/"):
            assert np.array_equal(ref[k], b[k]), k


def _wait_for(path, timeout=120):
    t0 = time.time()
    while not os.path.exists(path):
        assert time.time() - t0 < timeout, f"{path} never appeared"
        time.sleep(0.05)


def _start(args, cwd):
    env = dict(os.environ, PYTHONPATH=str(ROOT))
    return subprocess.Popen([sys.executable, "-m", "pdfem"] + args, cwd=cwd, env=env,
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)


def test_sigterm_checkpoints_and_the_restart_continues_the_run_file(tmp_path, reference):
    scene = _bed(tmp_path, 4000)
    proc = _start(["run", scene, "-o", "c.h5", "--quiet"], tmp_path)
    # The handler is in place before the run file appears; a short wait lets a few steps run
    # (the whole run takes about a second: a longer wait could miss it)
    _wait_for(tmp_path / "c.h5.part")
    time.sleep(0.1)
    proc.send_signal(signal.SIGTERM)
    out, err = proc.communicate(timeout=120)
    assert proc.returncode == 0, err
    assert (tmp_path / "c.h5.ckpt.h5").exists() and (tmp_path / "c.h5.part").exists()
    assert not (tmp_path / "c.h5").exists()
    # Continue on 2 ranks into the same run file: equal to the run that never stopped
    p = pdfem(["run", scene, "--restart", "c.h5.ckpt.h5", "-o", "c.h5", "--quiet"], tmp_path,
              ranks=2)
    assert p.returncode == 0, p.stderr
    _same(reference, tmp_path / "c.h5")


def _catches_sigterm(pid):
    """True once process ``pid`` has a handler for SIGTERM (its SigCgt mask, Linux)."""
    with open(f"/proc/{pid}/status") as f:
        mask = next(line for line in f if line.startswith("SigCgt:")).split()[1]
    return bool(int(mask, 16) >> (signal.SIGTERM - 1) & 1)


def test_sigterm_during_start_up_ends_in_a_checkpoint(tmp_path, reference):
    """A SIGTERM that arrives while the process still imports and sets up (as soon as
    python -m pdfem holds the signal, long before the first step) ends the run after its
    first step with a checkpoint and status 0; the restart on 2 ranks ends equal to the
    uninterrupted run."""
    scene = _bed(tmp_path, 4000)
    proc = _start(["run", scene, "-o", "e.h5", "--quiet"], tmp_path)
    t0 = time.time()
    while not _catches_sigterm(proc.pid):
        assert time.time() - t0 < 60 and proc.poll() is None
        time.sleep(0.001)
    # Held before numba (and so the solver) is even loaded
    with open(f"/proc/{proc.pid}/maps") as f:
        assert "llvmlite" not in f.read()
    proc.send_signal(signal.SIGTERM)
    out, err = proc.communicate(timeout=120)
    assert proc.returncode == 0, err
    with h5py.File(tmp_path / "e.h5.ckpt.h5") as f:
        assert json.loads(f.attrs["state"])["nstep"] == 1
    p = pdfem(["run", scene, "--restart", "e.h5.ckpt.h5", "-o", "e.h5", "--quiet"], tmp_path,
              ranks=2)
    assert p.returncode == 0, p.stderr
    _same(reference, tmp_path / "e.h5")


def test_sigterm_ends_a_command_that_runs_no_simulation(tmp_path):
    """Commands other than run get the default action back: SIGTERM ends them at once."""
    proc = _start(["study", "convergence"], tmp_path)
    # Held from the entry point, then released once the command is known
    for held in (True, False):
        t0 = time.time()
        while _catches_sigterm(proc.pid) != held:
            assert time.time() - t0 < 60 and proc.poll() is None
            time.sleep(0.001)
    proc.send_signal(signal.SIGTERM)
    proc.communicate(timeout=60)
    assert proc.returncode == -signal.SIGTERM


def test_sigkill_of_a_run_checkpointing_every_step_keeps_a_readable_one(tmp_path, reference):
    # A checkpoint after every step: a kill lands in (or between) checkpoint writes
    scene = _bed(tmp_path, 4000, "\ncheckpoint_interval = 1.0e-12")
    proc = _start(["run", scene, "-o", "k.h5", "--quiet"], tmp_path)
    _wait_for(tmp_path / "k.h5.ckpt.h5")
    time.sleep(1.5)
    proc.kill()
    proc.communicate(timeout=60)
    ck = tmp_path / "k.h5.ckpt.h5"
    with h5py.File(ck) as f:
        assert f.attrs["format"] == 1
    # The restart (without frequent checkpoints) ends equal to the uninterrupted run
    _bed(tmp_path, 4000)
    p = pdfem(["run", scene, "--restart", str(ck), "-o", "k.h5", "--quiet"], tmp_path)
    assert p.returncode == 0, p.stderr
    ref, k = datasets(reference), datasets(tmp_path / "k.h5")
    assert np.array_equal(ref["frames/x"][-1], k["frames/x"][-1])
    assert np.array_equal(ref["energy/kinetic"], k["energy/kinetic"])


def test_restart_of_another_scene_is_refused(tmp_path, reference):
    scene = _bed(tmp_path, 4000, "\ncheckpoint_interval = 2.0e-5")
    assert pdfem(["run", scene, "-o", "a.h5", "--quiet"], tmp_path).returncode == 0
    text = (tmp_path / scene).read_text().replace("gamma = 20000.0", "gamma = 30000.0")
    (tmp_path / "other.toml").write_text(text)
    p = pdfem(["run", "other.toml", "--restart", "a.h5.ckpt.h5", "-o", "o.h5"], tmp_path)
    assert p.returncode == 2 and "different scene ([damping] differs" in p.stderr, p.stderr


FAIL_ON_RANK_1 = """
import sys
from mpi4py import MPI
from pdfem.solver import Simulation
from pdfem.cli import main

step = Simulation.step

def failing(self):
    if MPI.COMM_WORLD.rank == 1 and self.nstep == 50:
        raise RuntimeError("injected failure on rank 1")
    step(self)

Simulation.step = failing
sys.exit(main(sys.argv[1:]))
"""


def test_exception_on_one_rank_aborts_the_run(tmp_path):
    scene = _bed(tmp_path, 100000)
    (tmp_path / "fail.py").write_text(FAIL_ON_RANK_1)
    env = dict(os.environ, PYTHONPATH=str(ROOT))
    t0 = time.time()
    p = subprocess.run(MPIRUN + ["-n", "2", sys.executable, "fail.py", "run", scene, "-o",
                                 "f.h5", "--quiet"], cwd=tmp_path, env=env, capture_output=True,
                       text=True, timeout=120)
    assert p.returncode != 0
    assert "injected failure on rank 1" in p.stderr
    assert time.time() - t0 < 60


def test_killed_rank_ends_mpirun(tmp_path):
    scene = _bed(tmp_path, 100000)
    env = dict(os.environ, PYTHONPATH=str(ROOT))
    proc = subprocess.Popen(MPIRUN + ["-n", "2", sys.executable, "-m", "pdfem", "run", scene,
                                      "-o", "m.h5", "--quiet"], cwd=tmp_path, env=env,
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    _wait_for(tmp_path / "m.h5.part")
    time.sleep(1.0)
    # Kill one rank (the newest python process running this scene)
    pids = subprocess.run(["pgrep", "-f", "-n", "pdfem run bed.toml -o m.h5"],
                          capture_output=True, text=True).stdout.split()
    assert pids
    os.kill(int(pids[0]), signal.SIGKILL)
    proc.communicate(timeout=60)
    assert proc.returncode != 0


def test_checkpoint_reader_names_a_bad_file(tmp_path):
    from pdfem.errors import InputError

    bad = Path(tmp_path / "x.h5")
    with h5py.File(bad, "w") as f:
        f.attrs["format"] = 99
    with pytest.raises(InputError, match="not a pdfem checkpoint"):
        read_checkpoint(str(bad), [])


def test_rebalancing_moves_cells_and_keeps_results_bit_identical(tmp_path):
    # The bed falls onto the floor: the rcb cut made for the loose rows at t = 0 leaves the
    # ranks unequal once it has settled (6000 steps: the 4000 of the reference stay balanced
    # to within 5 % at every rebuild)
    text = (tmp_path / _bed(tmp_path, 6000)).read_text()
    (tmp_path / "ref.toml").write_text(text)
    p = pdfem(["run", "ref.toml", "-o", "ref.h5", "--quiet"], tmp_path)
    assert p.returncode == 0, p.stderr
    (tmp_path / "rb.toml").write_text(
        text.replace('partition = "rcb"', 'partition = "rcb"\nrebalance = 1.05'))
    p = pdfem(["run", "rb.toml", "-o", "rb.h5"], tmp_path, ranks=2)
    assert p.returncode == 0, p.stderr
    moved = [ln for ln in p.stdout.splitlines() if "rebalanced" in ln]
    assert moved and int(moved[0].split("rebalanced ")[1].split()[0]) >= 1, p.stdout
    _same(tmp_path / "ref.h5", tmp_path / "rb.h5")


def test_point_gauge_keeps_its_element_across_a_restart_on_another_rank_count(tmp_path):
    """A point gauge samples the element that held its point at t = 0, also after a restart
    on another number of ranks, when its grain has drifted away from the point: every
    /gauges dataset of the restarted run equals the uninterrupted run's."""
    from tests.scenes import drifting_grains

    gauge = '\n[[gauges]]\nname = "p"\npoint = [0.002, 0.0015]\n'
    out = "\ngauge_interval = 2.0e-7\ncheckpoint_interval = 3.0e-6"
    scene = drifting_grains(end=4.0e-6, extra=gauge).replace(
        "interval = 1e-06", "interval = 1e-06" + out)
    assert "checkpoint_interval" in scene
    (tmp_path / "g.toml").write_text(scene)
    p = pdfem(["run", "g.toml", "-o", "ref.h5", "--quiet"], tmp_path)
    assert p.returncode == 0, p.stderr
    p = pdfem(["run", "g.toml", "--restart", "ref.h5.ckpt.h5", "-o", "b.h5", "--quiet"],
              tmp_path, ranks=2)
    assert p.returncode == 0, p.stderr
    ref, b = datasets(tmp_path / "ref.h5"), datasets(tmp_path / "b.h5")
    keys = [k for k in ref if k.startswith("gauges/")]
    assert "gauges/p/elements" in keys and "gauges/p/velocity" in keys
    for k in keys:
        assert np.array_equal(ref[k], b[k]), f"{k} differs after the restart"
    # The gauge's grain has left the point by the checkpoint: a new search would not find it
    with h5py.File(tmp_path / "ref.h5") as f:
        v = f["gauges/p/velocity"][:]
    assert np.all(np.abs(v[:, 0]) * 3.0e-6 > 4.0e-4)
