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
import math
import os
import tempfile
import tomllib

import h5py
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from pdfem.cli import main
from pdfem.scene.toml_out import dumps
from tests.scenes import ELASTIC

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
{ELASTIC}
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

# Replacement values: wrong types, signs, zero, non-finite, huge, empty
BAD_VALUES = ["text", "", True, [], {}, [1.0], [1.0, 2.0, 3.0], -1.0, -1, 0, 0.0, math.nan,
              math.inf, -math.inf, 1.0e300, -1.0e300, 10**12, 2**70, 1.0e-300]
# Factors on a number (or every number of a list): still valid or just out of range (an
# integer such as a block's nx only grows to what stays a small run, or far beyond the limit)
FACTORS = [-1.0, 0.0, 1.0e-6, 0.5, 2.0, 1.0e6, 1.0e300]
INT_FACTORS = [-1, 0, 2, 10**12]
# Unknown names, some one typo away from a real key or effect
UNKNOWN = ["bogus", "gama", "viscosityy", "frictional_heating", "heat_", "Domain", "x y",
           "__import__", "!!python/object"]


def _paths(node, path=()):
    """Every key path (tuple of keys and list indices) inside a parsed TOML document."""
    items = node.items() if isinstance(node, dict) else enumerate(node) \
        if isinstance(node, list) else ()
    for k, v in items:
        yield path + (k,)
        yield from _paths(v, path + (k,))


def _parent(doc, path):
    for k in path[:-1]:
        doc = doc[k]
    return doc


def _scaled(v, k):
    """``v`` (a number or a list of them) scaled by FACTORS[k] or, an integer, INT_FACTORS."""
    if isinstance(v, list):
        return [_scaled(x, k) for x in v]
    if isinstance(v, bool) or not isinstance(v, (int, float)):
        return v
    return v * (INT_FACTORS[k % len(INT_FACTORS)] if isinstance(v, int) else FACTORS[k])


@st.composite
def mutants(draw, base=BASE):
    """(file bytes, what was done) of the scene text ``base`` mutated once."""
    doc = tomllib.loads(base)
    text = dumps(doc)
    kind = draw(st.sampled_from(["replace", "replace", "scale", "delete", "unknown key",
                                 "unknown table", "truncate", "garbage"]))
    if kind == "truncate":
        k = draw(st.integers(0, len(text) - 1))
        return text[:k].encode(), f"truncated at {k}"
    if kind == "garbage":
        junk = draw(st.sampled_from([b"\x89HDF\r\n\x1a\n\x00\x00", bytes(range(256)),
                                     b"[[[", b"= 1", b"a = \"unterminated", b"\xff\xfe"]))
        k = draw(st.integers(0, len(text)))
        return text[:k].encode() + junk + text[k:].encode(), f"garbage at {k}"
    if kind == "unknown table":
        name = draw(st.sampled_from(UNKNOWN))
        doc[name] = {"x": 1.0}
        return dumps(doc).encode(), f"table [{name}]"
    path = draw(st.sampled_from(list(_paths(doc))))
    parent = _parent(doc, path)
    if kind == "delete":
        del parent[path[-1]]
    elif kind == "unknown key":
        target = parent[path[-1]]
        tables = target if isinstance(target, dict) else parent if isinstance(parent, dict) \
            else None
        if tables is None:
            return text.encode(), "unchanged"
        tables[draw(st.sampled_from(UNKNOWN))] = 1.0
    elif kind == "scale":
        parent[path[-1]] = _scaled(parent[path[-1]], draw(st.integers(0, len(FACTORS) - 1)))
    else:
        # An item of an array of tables stays a table (the TOML writer has no inline tables)
        values = BAD_VALUES if isinstance(parent, dict) else [{}, {"bogus": 1.0}] \
            if all(isinstance(x, dict) for x in parent) else BAD_VALUES[:4] + BAD_VALUES[5:]
        parent[path[-1]] = draw(st.sampled_from(values))
    return dumps(doc).encode(), f"{kind} {'.'.join(map(str, path))}"


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
@given(mutants())
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
