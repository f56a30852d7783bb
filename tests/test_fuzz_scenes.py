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
"""

import contextlib
import io
import os
import tempfile

import h5py
from hypothesis import HealthCheck, given, settings

from pdfem.cli import main
from tests.fuzz import mutants
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

def _run(folder, data):
    """``pdfem run`` on the scene bytes in ``folder``: (exit status, stdout, stderr)."""
    with open(os.path.join(folder, "s.toml"), "wb") as f:
        f.write(data)
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
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
