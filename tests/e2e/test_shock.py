"""Sample preparation and a small shock run through the real command line.

The preparation of a bed is bit-for-bit the same on 1 and 2 ranks; a hammer at 288 m/s into
a small prepared bed (2 grains wide) on 2 ranks gives a compaction front that reaches the
bottom, a front speed between the snowplow bound and the grains' elastic wave speed, jump
conditions that close within 15 % and an energy balance within 2 %.
"""

import json
import re

import h5py
import numpy as np
import pytest

from tests.e2e.test_cli import datasets, pdfem
from tests.scenes import prep_scene, shock_scene


def _attrs(path):
    with h5py.File(path) as f:
        return dict(f.attrs)


def test_preparation_is_identical_on_1_and_2_ranks(tmp_path):
    (tmp_path / "p.toml").write_text(prep_scene(grains=8, seed=11))
    for n in (1, 2):
        p = pdfem(["prepare", "p.toml", "-o", f"bed{n}.h5"], tmp_path, ranks=n)
        assert p.returncode == 0, p.stderr
        assert "packing fraction" in p.stdout
    a, b = datasets(tmp_path / "bed1.h5"), datasets(tmp_path / "bed2.h5")
    assert sorted(a) == sorted(b)
    for k in a:
        assert np.array_equal(a[k], b[k]), f"{k} differs on 2 ranks"
    at = _attrs(tmp_path / "bed1.h5")
    assert at["packing_fraction"] == _attrs(tmp_path / "bed2.h5")["packing_fraction"]
    # Every phase came to rest; the bed is denser than a loose lattice, below close packing
    assert at["converged"]
    assert 0.5 < at["packing_fraction"] < 0.95
    assert not any(p.name.endswith(".part") or ".rain." in p.name for p in tmp_path.iterdir())


@pytest.fixture(scope="module")
def small_bed(tmp_path_factory):
    """A 20-grain bed, 2 grains wide, prepared on 2 ranks."""
    d = tmp_path_factory.mktemp("bed")
    (d / "p.toml").write_text(prep_scene(grains=20, height=4.5e-3, seed=7))
    p = pdfem(["prepare", "p.toml", "-o", "bed.h5"], d, ranks=2)
    assert p.returncode == 0, p.stderr
    return d / "bed.h5"


def test_small_shock_on_2_ranks(small_bed, tmp_path):
    top = float(_attrs(small_bed)["bed_top"])
    (tmp_path / "s.toml").write_text(shock_scene(str(small_bed), top + 1.0e-5,
                                                 height=top + 5.0e-4, end=2.5e-6))
    p = pdfem(["run", "s.toml", "-o", "shock.h5"], tmp_path, ranks=2)
    assert p.returncode == 0, p.stderr
    assert "Us =" in p.stdout
    s = json.loads((tmp_path / "shock-summary.json").read_text())
    front, jump = s["front"], s["jump"]
    # The compaction front reaches the bottom within the run
    assert front["us"] is not None and front["arrival_fit"] is not None
    assert front["arrival_fit"] < 2.5e-6
    # Us between the snowplow bound (a compaction wave into rigid grains, rho1 <= rho_s) and
    # the grains' longitudinal wave speed (no signal is faster)
    assert s["snowplow"]["us"] < front["us"] < s["elastic_wave_speed"]
    # Jump conditions: mass, and momentum with the stress that decelerates the hammer
    assert jump["mass_closure"] < 0.15
    assert jump["momentum_closure_deceleration"] < 0.15
    assert s["energy"]["balance_error_last"] < 0.02
    assert (tmp_path / "shock-summary.txt").stat().st_size > 0


BAD_PREPARE = {
    "no prepare table": ("", "prepare: the scene has no [prepare] table"),
    "unknown weight": ('weight = "anvil"', "prepare.weight: unknown block"),
    "too many grains": ("grains = 500", "prepare.grains: 500 grains need"),
    "reversed range": ("semi_axis = [2.0e-4, 1.0e-4]", "prepare.semi_axis: min must be <= max"),
}


@pytest.mark.parametrize("case", sorted(BAD_PREPARE))
def test_bad_preparation_input(tmp_path, case):
    change, msg = BAD_PREPARE[case]
    text = prep_scene(grains=8)
    if case == "no prepare table":
        text = text[: text.index("[prepare]")]
    else:
        key = change.split(" = ")[0]
        text = re.sub(rf"(?m)^{key} = .*$", change, text)
    (tmp_path / "p.toml").write_text(text)
    (tmp_path / "keep.h5").write_bytes(b"precious")
    p = pdfem(["prepare", "p.toml", "-o", "keep.h5", "--force"], tmp_path)
    assert p.returncode == 2, p.stderr
    assert msg in p.stderr and len(p.stderr.strip().splitlines()) == 1, p.stderr
    assert (tmp_path / "keep.h5").read_bytes() == b"precious"


def test_prepare_never_overwrites_without_force(tmp_path):
    (tmp_path / "p.toml").write_text(prep_scene(grains=8))
    (tmp_path / "bed.h5").write_bytes(b"precious")
    p = pdfem(["prepare", "p.toml"], tmp_path)
    assert p.returncode == 2 and "prepare.output" in p.stderr and "exists" in p.stderr
    assert (tmp_path / "bed.h5").read_bytes() == b"precious"


def test_sweep_on_2_ranks(small_bed, tmp_path):
    top = float(_attrs(small_bed)["bed_top"])
    (tmp_path / "s.toml").write_text(shock_scene(str(small_bed), top + 1.0e-5,
                                                 height=top + 5.0e-4, end=2.0e-6))
    p = pdfem(["sweep", "s.toml", "--velocities", "150,300", "-p", "sw"], tmp_path, ranks=2)
    assert p.returncode == 0, p.stderr
    pts = json.loads((tmp_path / "sw.json").read_text())
    assert [q["velocity"] for q in pts] == [150.0, 300.0]
    # A harder blow drives a faster particle velocity and a higher stress
    assert pts[1]["up"] > pts[0]["up"] > 0 and pts[1]["sigma"] > pts[0]["sigma"]
    assert (tmp_path / "sw.png").read_bytes()[:4] == b"\x89PNG"


@pytest.mark.parametrize("args,msg", [
    (["sweep", "s.toml", "--velocities", "fast"], "--velocities: not a list of numbers"),
    (["sweep", "s.toml", "--velocities=0,-5"], "--velocities: need speeds > 0"),
    (["analyse", "missing.h5"], "missing.h5: no such run file"),
])
def test_bad_sweep_and_analyse_input(tmp_path, args, msg):
    (tmp_path / "s.toml").write_text(shock_scene("bed.h5", 1.0e-3))
    p = pdfem(args, tmp_path)
    assert p.returncode == 2 and msg in p.stderr, p.stderr
    assert len(p.stderr.strip().splitlines()) == 1
