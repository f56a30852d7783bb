"""Bad input never hurts: mutated scenes through the ``run`` command, in process.

A small valid scene (grains, a block with a boundary condition and a gauge, contact, walls,
gravity, damping) is mutated once: a key or table deleted, a value replaced by a wrong type,
a negative, zero, NaN, infinite, huge or empty value, a value scaled, an unknown key or
table (an unknown effect name) added, the text cut short or replaced by garbage. Then
``pdfem.cli.main(["run", ...])`` either succeeds (the mutant was still a valid scene: the
run file is complete HDF5) or exits 2 with exactly one line on stderr naming the problem, no
traceback and no file left behind. A valid scene whose run then fails a guard (a gravity of
1e12 m/s^2 inverts an element in the first step) exits 3, also with one line, naming the
step, and leaves no run file under its final name: only the checkpoint of the last good
state and the run file's ``.part`` that a restart continues.

Every key that sets a schedule (time.end, the output, energy, gauge and checkpoint intervals,
the checkpoint wall time, a boundary condition's release and ramp-down) is also given each of
tests.fuzz.EXTREME_TIMES, from the smallest subnormal to the largest float: the run either
completes or is refused before its first step with one line naming that key, or one derived
from it. Every example runs under an alarm, so a run that spins fails instead of hanging.
"""

import contextlib
import io
import os
import tempfile
import tomllib

import h5py
import pytest
from hypothesis import HealthCheck, given, settings

from pdfem.cli import main
from pdfem.scene.toml_out import dumps
from tests.fuzz import EXTREME_TIMES, alarm, mutants, schedule_keys, schedule_name
from tests.scenes import elastic, toml

# A few steps (time.max_steps bounds a mutated end time or safety factor)
BASE = f"""
[domain]
box = [0.0, 0.0, 0.004, 0.003]
cell_size = 1.0e-3
skin = 5.0e-5

[time]
end = 2.0e-8
safety = 0.5
max_steps = 3

[element]
rule = "1pt"
level = 1

[gravity]
g = [0.0, -9.81]

[damping]
gamma = 10.0

[contact]
kn0 = 1.0e15
delta_max = 2.0e-5
friction = 0.3

[walls]
left = "frictionless"
bottom = "frictional"
friction = 0.3

[output]
path = "scene-out.h5"
interval = 1.0e-8
fields = ["x", "v", "stress"]

{toml({"materials": {"grain": elastic()}})}
[[grains]]
center = [0.0012, 0.0012]
axes = [4.0e-4, 3.0e-4]
angle = 0.3
material = "grain"
velocity = [20.0, 0.0]

[[grains]]
center = [0.0025, 0.0015]
axes = [4.0e-4, 4.0e-4]
material = "grain"

[[blocks]]
name = "floor"
box = [0.0, 0.0, 0.004, 2.0e-4]
nx = 4
ny = 1
material = "grain"

[[bc]]
body = "floor"
nodes = "bottom"
type = "fixed"

[[gauges]]
name = "g"
body = "floor"
side = "top"
"""

# The base with a velocity condition that is ramped down and released (two more schedules)
SCHEDULED = BASE + """
[[bc]]
body = "floor"
nodes = "top"
type = "velocity"
velocity = [0.0, 1.0]
release = 1.0e-8
ramp_down = 5.0e-9
"""
# Seconds a mutant's run may take before it counts as a hang (three steps take well under one)
LIMIT = 60


def _run(folder, data):
    """``pdfem run`` on the scene bytes in ``folder``: (exit status, stdout, stderr)."""
    with open(os.path.join(folder, "s.toml"), "wb") as f:
        f.write(data)
    out, err = io.StringIO(), io.StringIO()
    with alarm(LIMIT), contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        status = main(["run", os.path.join(folder, "s.toml"), "-o",
                       os.path.join(folder, "out.h5"), "--quiet"])
    return status, out.getvalue(), err.getvalue()


def test_the_base_scene_runs():
    with tempfile.TemporaryDirectory() as d:
        status, _, err = _run(d, BASE.encode())
        assert status == 0, err
        with h5py.File(os.path.join(d, "out.h5")) as f:
            assert f["frames/time"].shape[0] >= 2


@settings(max_examples=300, deadline=None, derandomize=True,
          suppress_health_check=[HealthCheck.too_slow])
@given(mutants(BASE))
def test_mutated_scene_runs_or_exits_2_with_one_line(mutant):
    data, what = mutant
    with tempfile.TemporaryDirectory() as d:
        status, _, err = _run(d, data)
        assert "Traceback" not in err, (what, err)
        left = sorted(set(os.listdir(d)) - {"s.toml"})
        if status == 0:
            # Still a valid scene: a complete run file
            assert "out.h5" in left, (what, left)
            with h5py.File(os.path.join(d, "out.h5")) as f:
                assert f["frames/time"].shape[0] >= 1 and "energy" in f, what
            assert not [n for n in left if n.endswith(".part")], (what, left)
            return
        assert status in (2, 3), (what, status, err)
        lines = err.strip().splitlines()
        assert len(lines) == 1 and lines[0].startswith("pdfem: error: "), (what, err)
        if status == 2:
            assert left == [], (what, left)
        else:
            assert lines[0].startswith("pdfem: error: step "), (what, err)
            # The last good state, and the frame segments of the run so far
            assert all(n in {"out.h5.ckpt.h5", "out.h5.part"} or n.startswith("out.h5.part.")
                       for n in left), (what, left)


def test_the_scheduled_base_runs():
    with tempfile.TemporaryDirectory() as d:
        status, _, err = _run(d, SCHEDULED.encode())
        assert status == 0, err


def _scheduled(path, value, bounded=True):
    """SCHEDULED with the schedule key at ``path`` set to ``value``: scene bytes; bounded:
    keep its time.max_steps (which also bounds how many outputs an interval implies)."""
    doc = tomllib.loads(SCHEDULED)
    if not bounded:
        del doc["time"]["max_steps"]
    parent = doc
    for k in path[:-1]:
        parent = parent[k]
    parent[path[-1]] = value
    return dumps(doc).encode()


# Every schedule key of the scene with every extreme time (tests/fuzz.py)
SCHEDULE_CASES = [(schedule_name(p), p, v) for p in schedule_keys(tomllib.loads(SCHEDULED))
                  for v in EXTREME_TIMES]


# And the output keys without time.max_steps, where the count over time.end is the bound
UNBOUNDED_CASES = [(k, p, v, False) for k, p, v in SCHEDULE_CASES if p[0] == "output"]
ALL_CASES = [(k, p, v, True) for k, p, v in SCHEDULE_CASES] + UNBOUNDED_CASES


@pytest.mark.parametrize("key,path,value,bounded", ALL_CASES,
                         ids=[f"{k}={v!r}{'' if b else '-unbounded'}" for k, _, v, b in ALL_CASES])
def test_extreme_schedule_runs_or_is_refused_naming_the_key(key, path, value, bounded):
    data = _scheduled(path, value, bounded)
    what = f"{key} = {value!r}"
    with tempfile.TemporaryDirectory() as d:
        status, _, err = _run(d, data)
        left = sorted(set(os.listdir(d)) - {"s.toml"})
        assert "Traceback" not in err, (what, err)
        if status == 0:
            with h5py.File(os.path.join(d, "out.h5")) as f:
                assert f["frames/time"].shape[0] >= 1, what
            return
        assert status == 2, (what, status, err)
        lines = err.strip().splitlines()
        assert len(lines) == 1 and len(lines[0]) < 200, (what, err)
        # The key, or one checked with it (an interval derived from it, bc[1].ramp_down against
        # bc[1].release, an interval against time.end) that names it
        leaf = key.rsplit(".", 1)[-1]
        assert key in lines[0] or (leaf in lines[0] and key.split(".")[0] in lines[0]) or (
            leaf.endswith("interval") and "interval" in lines[0]), (what, lines[0])
        assert left == [], (what, left)


def test_a_torn_grain_stops_on_a_guard():
    """Gravity of 1e300 m/s^2 tears a grain across the box in a step: the run stops on a guard
    with one line (the contact reach of the rebuild is capped at the grid's size, where it
    sized arrays beyond memory)."""
    with tempfile.TemporaryDirectory() as d:
        status, _, err = _run(d, BASE.replace("g = [0.0, -9.81]", "g = [1e300, -9.81]").encode())
        assert status == 3, err
        lines = err.strip().splitlines()
        assert len(lines) == 1 and lines[0].startswith("pdfem: error: step "), err
