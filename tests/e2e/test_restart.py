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

from pdfem.io.checkpoint import FORMAT, read_checkpoint
from tests.helpers import MPIRUN, ROOT, datasets, pdfem
from tests.scenes import settling_bed, write_scene


def _bed_doc(steps, checkpoint=None):
    """The settling bed of these tests: ``steps`` steps, a frame every 2e-5 s, a checkpoint
    every ``checkpoint`` s when given."""
    doc = settling_bed(n=60, cols=10, end=1.0, partition="rcb")
    doc["time"]["max_steps"] = steps
    doc["output"]["interval"] = 2.0e-5
    if checkpoint is not None:
        doc["output"]["checkpoint_interval"] = checkpoint
    return doc


def _bed(tmp_path, steps, checkpoint=None):
    """Write _bed_doc as bed.toml in tmp_path; return its name."""
    write_scene(tmp_path / "bed.toml", _bed_doc(steps, checkpoint))
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


@pytest.mark.parametrize("ranks", [1, 3, 4])
def test_restart_is_bit_identical(tmp_path, reference, ranks):
    scene = _bed(tmp_path, 4000, 1.5e-5)
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


def _checkpoint_datasets(path):
    """{name: values} of every dataset and attribute of a checkpoint but its rank count."""
    out = {}
    with h5py.File(path) as f:
        f.visititems(lambda name, d: out.__setitem__(name, d[...])
                     if isinstance(d, h5py.Dataset) else None)
        out.update({f"@{k}": v for k, v in f.attrs.items() if k != "nranks"})
    return out


def test_checkpoint_is_the_same_file_on_any_number_of_ranks(tmp_path):
    """Every rank writes its block of the global numbering: the checkpoint written on 1, 2
    and 3 ranks holds the same bytes in every dataset (bodies, nodes, elements, contact
    history by body, driver series)."""
    scene = _bed(tmp_path, 1500, 1.5e-5)
    files = []
    for ranks in (1, 2, 3):
        p = pdfem(["run", scene, "-o", f"r{ranks}.h5", "--quiet"], tmp_path, ranks=ranks)
        assert p.returncode == 0, p.stderr
        files.append(_checkpoint_datasets(tmp_path / f"r{ranks}.h5.ckpt.h5"))
    one = files[0]
    assert one["history/key"].shape[0] > 0 and "nodes/contact_force" in one
    assert np.count_nonzero(one["nodes/contact_force"]) > 0
    for other in files[1:]:
        assert sorted(other) == sorted(one)
        for k in one:
            if k != "@state":
                assert np.array_equal(one[k], other[k]), k
        # The state differs only in the run file's segment paths' folder (the same here)
        assert json.loads(other["@state"]) == json.loads(one["@state"]) | {
            "run_file": json.loads(other["@state"])["run_file"]}


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
    scene = _bed(tmp_path, 4000, 1.0e-12)
    proc = _start(["run", scene, "-o", "k.h5", "--quiet"], tmp_path)
    _wait_for(tmp_path / "k.h5.ckpt.h5")
    time.sleep(1.5)
    proc.kill()
    proc.communicate(timeout=60)
    ck = tmp_path / "k.h5.ckpt.h5"
    with h5py.File(ck) as f:
        assert f.attrs["format"] == FORMAT
    # The restart (without frequent checkpoints) ends equal to the uninterrupted run
    _bed(tmp_path, 4000)
    p = pdfem(["run", scene, "--restart", str(ck), "-o", "k.h5", "--quiet"], tmp_path)
    assert p.returncode == 0, p.stderr
    ref, k = datasets(reference), datasets(tmp_path / "k.h5")
    assert np.array_equal(ref["frames/x"][-1], k["frames/x"][-1])
    assert np.array_equal(ref["energy/kinetic"], k["energy/kinetic"])


def test_restart_of_another_scene_is_refused(tmp_path, reference):
    scene = _bed(tmp_path, 4000, 2.0e-5)
    assert pdfem(["run", scene, "-o", "a.h5", "--quiet"], tmp_path).returncode == 0
    doc = _bed_doc(4000, 2.0e-5)
    doc["damping"]["gamma"] = 30000.0
    write_scene(tmp_path / "other.toml", doc)
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
    t0 = time.time()
    os.kill(int(pids[0]), signal.SIGKILL)
    proc.communicate(timeout=60)
    assert proc.returncode != 0
    # Through jobs/mpirun.sh: mpirun ends the other rank (SIGTERM after 1 s, SIGKILL after 2)
    assert time.time() - t0 < 10


def test_checkpoint_reader_names_a_bad_file(tmp_path):
    from pdfem.errors import InputError

    bad = Path(tmp_path / "x.h5")
    with h5py.File(bad, "w") as f:
        f.attrs["format"] = 99
    with pytest.raises(InputError, match="not a pdfem checkpoint"):
        read_checkpoint(str(bad), [])


@pytest.mark.parametrize("damage", ["drop history/start", "grain rows", "string gid"])
def test_a_damaged_checkpoint_is_refused_on_every_rank(tmp_path, damage):
    """A checkpoint whose rows do not fit together is refused with one line and status 2
    on 2 ranks, though only one rank's block may hold the damage (no rank hangs)."""
    scene = _bed(tmp_path, 300, 1.0e-6)
    p = pdfem(["run", scene, "-o", "a.h5", "--quiet"], tmp_path)
    assert p.returncode == 0, p.stderr
    ck = tmp_path / "a.h5.ckpt.h5"
    with h5py.File(ck, "a") as f:
        if damage == "drop history/start":
            del f["history/start"]
        elif damage == "grain rows":
            # The last grain's gid points elsewhere: only the last rank's block sees it
            gid = f["bodies/gid"]
            gid[int((f["bodies/isglobal"][...] == 0).sum()) - 1] = 0
        else:
            del f["bodies/gid"]
            f["bodies/gid"] = np.array([b"a"] * f["bodies/nn"].shape[0])
    p = pdfem(["run", scene, "--restart", str(ck), "-o", "b.h5", "--quiet"], tmp_path,
              ranks=2, timeout=120)
    assert p.returncode == 2, p.stderr
    lines = [ln for ln in p.stderr.splitlines() if ln.strip()]
    assert len(set(lines)) == 1 and "is not a complete pdfem checkpoint" in lines[0], lines
    assert "Traceback" not in p.stderr
    assert not (tmp_path / "b.h5").exists() and not (tmp_path / "b.h5.part").exists()


def test_rebalancing_moves_cells_and_keeps_results_bit_identical(tmp_path):
    # The bed falls onto the floor: the rcb cut made for the loose rows at t = 0 leaves the
    # ranks unequal once it has settled (6000 steps: the 4000 of the reference stay balanced
    # to within 5 % at every rebuild)
    doc = _bed_doc(6000)
    write_scene(tmp_path / "ref.toml", doc)
    p = pdfem(["run", "ref.toml", "-o", "ref.h5", "--quiet"], tmp_path)
    assert p.returncode == 0, p.stderr
    doc["domain"]["rebalance"] = 1.05
    write_scene(tmp_path / "rb.toml", doc)
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

    scene = drifting_grains(end=4.0e-6, extra={"gauges": [{"name": "p",
                                                           "point": [0.002, 0.0015]}]})
    scene["output"].update(gauge_interval=2.0e-7, checkpoint_interval=3.0e-6)
    write_scene(tmp_path / "g.toml", scene)
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


# A run that SIGKILLs itself at a chosen moment: argv[1] the phase, argv[2] the count of
# that phase's events at which it dies (every rank counts the same collective events)
KILL_AT = """
import os
import signal
import sys

import h5py

import pdfem.io.h5out as h5out
import pdfem.io.restart as restart
from pdfem.cli import main

phase, at = sys.argv[1], int(sys.argv[2])
seen = [0]


def hit():
    seen[0] += 1
    if seen[0] == at:
        os.kill(os.getpid(), signal.SIGKILL)


if phase == "frame":
    # After a field of a frame is gathered: the earlier fields of the frame are written
    blocks = h5out.to_blocks

    def to_blocks(*args):
        out = blocks(*args)
        hit()
        return out

    h5out.to_blocks = to_blocks
elif phase == "checkpoint":
    # Rank 0 writes the checkpoint: its attributes and bodies are in, the file still open
    create = h5py.Group.create_dataset

    def create_dataset(self, name, *args, **kw):
        if name == "history/key" and self.file.filename.endswith(".ckpt.h5.part"):
            hit()
        return create(self, name, *args, **kw)

    h5py.Group.create_dataset = create_dataset
else:
    # Between the close of a frame segment and the checkpoint that lists it
    write = restart.write_checkpoint

    def write_checkpoint(*args):
        hit()
        return write(*args)

    restart.write_checkpoint = write_checkpoint
sys.argv[1:3] = []
sys.exit(main(sys.argv[1:]))
"""

def _kill_scene(folder, checkpoints=True):
    """Write the kill scene as k.toml in folder; return its name. Frames every 5e-7 s (33 of
    them), checkpoints every 2e-6 s when asked (at a frame: both schedules take the first step
    at or past a multiple), a gauge and the contact forces."""
    doc = settling_bed(n=60, cols=10, end=1.0, partition="rcb",
                       extra={"gauges": [{"name": "g", "point": [0.0008, 0.0003]}]})
    doc["time"]["max_steps"] = 1500
    doc["output"].update(interval=5.0e-7, gauge_interval=2.5e-7,
                         fields=["x", "v", "stress", "contact_force"])
    if checkpoints:
        doc["output"]["checkpoint_interval"] = 2.0e-6
    write_scene(folder / "k.toml", doc)
    return "k.toml"


@pytest.fixture(scope="module")
def kill_reference(tmp_path_factory):
    """The uninterrupted run of the kill scene without checkpoints (1 rank)."""
    d = tmp_path_factory.mktemp("kref")
    p = pdfem(["run", _kill_scene(d, checkpoints=False), "-o", "ref.h5", "--quiet"], d)
    assert p.returncode == 0, p.stderr
    return d / "ref.h5"


def _frames_in(path):
    """Frames of a closed segment file (0 when it does not open)."""
    try:
        with h5py.File(path) as f:
            return f["frames/time"].shape[0]
    except OSError:
        return 0


def _kill_moments():
    """(ranks, phase, count, restart ranks) of each kill, drawn with a fixed seed: frames
    after the first checkpoint (4 fields a frame, 4 mesh gathers first; the kill after the
    second field of the frame), checkpoints after the first."""
    rng = np.random.default_rng(2024)
    out = []
    for ranks, phases in ((1, ("frame", "checkpoint")), (2, ("frame", "checkpoint", "close"))):
        for phase in phases:
            if phase == "frame":
                n = 4 + 4 * int(rng.integers(6, 30)) + 2
            else:
                n = int(rng.integers(2, 8))
            out.append((ranks, phase, n, 3 - ranks))
    return out


@pytest.mark.parametrize("ranks,phase,at,again", _kill_moments())
def test_sigkill_at_any_moment_keeps_every_frame_up_to_the_checkpoint(
        tmp_path, kill_reference, ranks, phase, at, again):
    """SIGKILL during a frame write, during a checkpoint write, and between the close of a
    frame segment and its checkpoint, on 1 and 2 ranks; the restart on the other rank
    count ends in a run file equal in every dataset (frames, gauges, energy) to the run
    that never stopped."""
    scene = _kill_scene(tmp_path)
    (tmp_path / "kill.py").write_text(KILL_AT)
    cmd = [sys.executable, "kill.py", phase, str(at), "run", scene, "-o", "k.h5", "--quiet"]
    if ranks > 1:
        cmd = MPIRUN + ["-n", str(ranks)] + cmd
    p = subprocess.run(cmd, cwd=tmp_path, env=dict(os.environ, PYTHONPATH=str(ROOT)),
                       capture_output=True, text=True, timeout=300)
    assert p.returncode != 0 and not (tmp_path / "k.h5").exists(), p.stderr
    with h5py.File(tmp_path / "k.h5.ckpt.h5") as f:
        nseg = len(json.loads(f.attrs["state"]).get("segments", []))
    # What the kill left, before the restart deletes the segments the checkpoint lacks
    half_written = (tmp_path / "k.h5.ckpt.h5.part").exists()
    unlisted = tmp_path / f"k.h5.part.{nseg}"
    there, closed = unlisted.exists(), unlisted.exists() and _frames_in(unlisted)
    p = pdfem(["run", scene, "--restart", "k.h5.ckpt.h5", "-o", "k.h5", "--quiet"], tmp_path,
              ranks=again)
    assert p.returncode == 0, p.stderr
    assert "warning" not in p.stdout + p.stderr
    ref = datasets(kill_reference)
    assert {"frames/contact_force", "gauges/g/velocity", "energy/kinetic"} <= set(ref)
    assert ref["frames/time"].shape[0] == 34
    _same(kill_reference, tmp_path / "k.h5")
    # The kill landed in the intended phase: a checkpoint half written; a segment closed
    # that the checkpoint does not list; a frame of the segment after the checkpoint's
    assert nseg >= 1 and half_written == (phase == "checkpoint")
    if phase == "close":
        assert closed
    if phase == "frame":
        assert there
    # The segments are gone once the run file is in place
    assert sorted(q.name for q in tmp_path.glob("k.h5.part*")) == []


def test_restart_into_a_new_run_file_starts_with_the_checkpoints_contact_forces(
        tmp_path, kill_reference):
    """A restart into another run file (no segments to continue) starts it with a frame at
    the checkpoint's time: equal in every field, contact forces included, to the
    uninterrupted run's frame of that step (the old restart wrote zero forces)."""
    scene = _kill_scene(tmp_path)
    p = pdfem(["run", scene, "-o", "a.h5", "--quiet"], tmp_path)
    assert p.returncode == 0, p.stderr
    p = pdfem(["run", scene, "--restart", "a.h5.ckpt.h5", "-o", "n.h5", "--quiet"], tmp_path,
              ranks=2)
    assert p.returncode == 0, p.stderr
    assert "n.h5.part is missing" in p.stdout + p.stderr
    ref, n = datasets(kill_reference), datasets(tmp_path / "n.h5")
    j = int(np.nonzero(ref["frames/time"] == n["frames/time"][0])[0][0])
    assert n["frames/time"].shape[0] == ref["frames/time"].shape[0] - j >= 2
    assert np.abs(n["frames/contact_force"][0]).max() > 0.0
    for k in ref:
        if k.startswith("frames/"):
            assert np.array_equal(ref[k][j:], n[k]), k


def test_restart_refuses_a_damaged_segment(tmp_path):
    """A segment the checkpoint lists, damaged: one line naming the file, exit 2, and no lock
    file left."""
    scene = _kill_scene(tmp_path)
    (tmp_path / "kill.py").write_text(KILL_AT)
    p = subprocess.run([sys.executable, "kill.py", "close", "3", "run", scene, "-o", "k.h5",
                        "--quiet"], cwd=tmp_path, env=dict(os.environ, PYTHONPATH=str(ROOT)),
                       capture_output=True, text=True, timeout=300)
    assert p.returncode == -signal.SIGKILL
    (tmp_path / "k.h5.part.1").write_bytes(b"not hdf5")
    p = pdfem(["run", scene, "--restart", "k.h5.ckpt.h5", "-o", "k.h5"], tmp_path)
    assert p.returncode == 2 and "Traceback" not in p.stderr, p.stderr
    assert len(p.stderr.strip().splitlines()) == 1 and "k.h5.part.1" in p.stderr, p.stderr
    # The killed run's lock file was taken, and given back with the refusal
    assert not (tmp_path / "k.h5.lock").exists()


def _as_earlier_version(path):
    """Rewrite a checkpoint as versions before the total-form hourglass control wrote it: an
    element field hgq (ne, 2) after mst, and no hgref."""
    with h5py.File(path, "r+") as f:
        names = json.loads(f.attrs["fields"])
        ne = f["elems/mst"].shape[0]
        if "hgref" in names:
            del f["elems/hgref"]
            names.remove("hgref")
        f["elems/hgq"] = np.zeros((ne, 2))
        names.insert(names.index("mst") + 1, "hgq")
        f.attrs["fields"] = json.dumps(names)


def test_a_checkpoint_of_an_earlier_version_restarts_or_is_refused(tmp_path):
    """A 2x2 run's checkpoint that holds the unused hgq field restarts as if it had none; a
    1-point run's, whose hourglass forces were incremental, is refused in one line."""
    for rule in ("2x2", "1pt"):
        doc = _bed_doc(400, 2.0e-6)
        doc["element"]["rule"] = rule
        write_scene(tmp_path / f"{rule}.toml", doc)
        p = pdfem(["run", f"{rule}.toml", "-o", f"{rule}.h5", "--quiet"], tmp_path)
        assert p.returncode == 0, p.stderr
    p = pdfem(["run", "2x2.toml", "--restart", "2x2.h5.ckpt.h5", "-o", "now.h5", "--quiet"],
              tmp_path)
    assert p.returncode == 0, p.stderr
    _as_earlier_version(tmp_path / "2x2.h5.ckpt.h5")
    p = pdfem(["run", "2x2.toml", "--restart", "2x2.h5.ckpt.h5", "-o", "old.h5", "--quiet"],
              tmp_path)
    assert p.returncode == 0, p.stderr
    _same(tmp_path / "now.h5", tmp_path / "old.h5")
    _as_earlier_version(tmp_path / "1pt.h5.ckpt.h5")
    p = pdfem(["run", "1pt.toml", "--restart", "1pt.h5.ckpt.h5", "-o", "o.h5"], tmp_path)
    assert p.returncode == 2 and "1-point hourglass forces of an earlier version" in p.stderr
    assert len(p.stderr.strip().splitlines()) == 1, p.stderr


def test_a_second_run_on_the_same_run_file_stops_before_writing(tmp_path):
    """While a run writes c.h5 (its claim c.h5.lock held), a second run on c.h5 stops at
    set-up with one line and status 2, writing nothing; the first goes on untouched, and once
    it has stopped (SIGTERM: checkpoint, run file left as .part) the lock file is gone. A
    stale lock file, held by no process, does not stop a run."""
    scene = _bed(tmp_path, 400000)
    first = _start(["run", scene, "-o", "c.h5", "--quiet"], tmp_path)
    _wait_for(tmp_path / "c.h5.part")
    assert (tmp_path / "c.h5.lock").exists()
    before = sorted(os.listdir(tmp_path))
    second = pdfem(["run", scene, "-o", "c.h5", "--quiet"], tmp_path)
    assert second.returncode == 2, second.stderr
    assert second.stderr.strip() == ("pdfem: error: output.path: c.h5: another run is writing "
                                     "it now (it holds c.h5.lock)")
    assert first.poll() is None and sorted(os.listdir(tmp_path)) == before
    first.send_signal(signal.SIGTERM)
    out, err = first.communicate(timeout=120)
    assert first.returncode == 0, err
    assert (tmp_path / "c.h5.part").exists() and (tmp_path / "c.h5.ckpt.h5").exists()
    assert not (tmp_path / "c.h5.lock").exists()
    # A lock file left by a process that died holds nothing
    (tmp_path / "d.h5.lock").write_text("")
    p = pdfem(["run", _bed(tmp_path, 400), "-o", "d.h5", "--quiet"], tmp_path)
    assert p.returncode == 0, p.stderr
    assert (tmp_path / "d.h5").exists() and not (tmp_path / "d.h5.lock").exists()
