"""Sample preparation, a small shock run and the sweep through the real command line.

The preparation of a bed (rain or geometric) is bit-for-bit the same on 1 and 2 ranks; a
geometric bed reaches its packing uniformly through the depth; a piston at 288 m/s into the
small 0.65 bed on 2 ranks gives a steady compaction front at or above the snowplow bound,
jump conditions that close, an energy balance within 2 % and a bed that stays compacted.
"""

import json

import h5py
import numpy as np
import pytest

from tests.helpers import datasets, pdfem, sigterm_when
from tests.scenes import prep_scene, shock_scene, small_prepare, small_shock, write_scene


def _attrs(path):
    with h5py.File(path) as f:
        return dict(f.attrs)


def test_rain_preparation_is_identical_on_1_and_2_ranks(tmp_path):
    write_scene(tmp_path / "p.toml", prep_scene(grains=8, seed=11))
    for n in (1, 2):
        p = pdfem(["prepare", "p.toml", "-o", f"bed{n}.h5"], tmp_path, ranks=n)
        assert p.returncode == 0, p.stderr
        assert "packing: reached" in p.stdout and "packing by depth" in p.stdout
    a, b = datasets(tmp_path / "bed1.h5"), datasets(tmp_path / "bed2.h5")
    assert sorted(a) == sorted(b)
    for k in a:
        assert np.array_equal(a[k], b[k]), f"{k} differs on 2 ranks"
    at = _attrs(tmp_path / "bed1.h5")
    assert at["packing_fraction"] == _attrs(tmp_path / "bed2.h5")["packing_fraction"]
    # Every phase came to rest; the bed is denser than a loose lattice, below close packing
    assert at["converged"] and at["method"] == "rain"
    assert 0.5 < at["packing_whole"] < 0.95
    assert not any(p.name.endswith(".part") or ".rain." in p.name for p in tmp_path.iterdir())


def test_rain_refuses_a_loose_target(tmp_path):
    """The rain route packs densely: a target of 0.65 is refused with the packing reached,
    and no bed file is written."""
    doc = prep_scene(grains=8, seed=11)
    doc["prepare"]["packing"] = 0.65
    write_scene(tmp_path / "p.toml", doc)
    p = pdfem(["prepare", "p.toml", "-o", "bed.h5"], tmp_path, ranks=2)
    lines = p.stderr.strip().splitlines()
    assert p.returncode == 2 and len(lines) == 1, p.stderr
    assert "prepare.packing: 0.65 not reached: the bed's interior packs at 0." in lines[0]
    assert not (tmp_path / "bed.h5").exists()


def test_geometric_preparation(tmp_path):
    """The packaged small preparation: the target and the reached packing and the slices
    printed; reached within 0.01 of 0.65 at the crystal's density, every interior slice
    within 0.03, grains apart; the same bed bit for bit on 1 and 2 ranks."""
    write_scene(tmp_path / "p.toml", small_prepare())
    for n in (1, 2):
        p = pdfem(["prepare", "p.toml", "-o", f"bed{n}.h5"], tmp_path, ranks=n)
        assert p.returncode == 0, p.stderr
        assert "packing: target 0.650, reached 0.6" in p.stdout
        assert "packing by depth (8 slices" in p.stdout and "gaps to the nearest" in p.stdout
    a, b = datasets(tmp_path / "bed1.h5"), datasets(tmp_path / "bed2.h5")
    assert sorted(a) == sorted(b)
    for k in a:
        assert np.array_equal(a[k], b[k]), f"{k} differs on 2 ranks"
    at = _attrs(tmp_path / "bed1.h5")
    assert at["method"] == "geometric" and abs(at["packing_fraction"] - 0.65) <= 0.01
    inner = at["packing_slices"][1:-1]
    assert inner.size == 6 and np.all(np.abs(inner - 0.65) <= 0.03)
    assert at["bed_density"] == pytest.approx(0.65 * 1900.0, rel=0.01)
    assert at["gap_min"] > 0.0 and at["gap_median"] > at["gap_min"]


def test_geometric_preparation_refuses_a_jammed_target(tmp_path):
    """A packing the grains cannot reach: one line naming prepare.packing and the packing
    reached, exit status 2, nothing written."""
    write_scene(tmp_path / "p.toml", small_prepare(packing=0.92))
    (tmp_path / "bed.h5").write_bytes(b"precious")
    p = pdfem(["prepare", "p.toml", "--force"], tmp_path)
    lines = p.stderr.strip().splitlines()
    assert p.returncode == 2 and len(lines) == 1, p.stderr
    assert "prepare.packing: 0.92 is too dense for the geometric route: the grains jammed at " \
        "a packing of 0." in lines[0]
    assert (tmp_path / "bed.h5").read_bytes() == b"precious"


@pytest.fixture(scope="module")
def small_bed(tmp_path_factory):
    """The packaged small geometric bed (1 mm x 2 mm at 0.65), prepared on 2 ranks."""
    d = tmp_path_factory.mktemp("bed")
    write_scene(d / "p.toml", small_prepare())
    p = pdfem(["prepare", "p.toml", "-o", "bed.h5"], d, ranks=2)
    assert p.returncode == 0, p.stderr
    return d / "bed.h5"


def test_small_shock_on_2_ranks(small_bed, tmp_path):
    """The CI-sized shot: a piston at 288 m/s into the small 0.65 bed, brought to rest and
    released. The front runs at or above the snowplow bound of its measured up, the mass
    jump closes in strain form within 15 %, the energy balance within 2 %, the bed ends
    compacted (at least half of the peak compaction kept), the anvil holds the reshock of the
    compacted bed; the run file is the same on 1 rank."""
    write_scene(tmp_path / "s.toml", small_shock(small_bed))
    p = pdfem(["run", "s.toml"], tmp_path, ranks=2)
    assert p.returncode == 0, p.stderr
    assert "Us =" in p.stdout and "precursor" in p.stdout
    s = json.loads((tmp_path / "shock-summary.json").read_text())
    bed, front, jump, comp = s["bed"], s["front"], s["jump"], s["compaction"]
    assert abs(bed["phi0"] - 0.65) <= 0.01 and abs(bed["rho0"] - 1235.0) <= 0.02 * 1240.0
    assert s["drive"]["kind"] == "piston" and s["drive"]["face_deviation"] < 0.05
    assert front["us"] is not None and front["us"] >= s["snowplow"]["us"]
    assert s["precursor"]["us_fit"] is not None
    assert jump["mass_strain_closure"] < 0.15
    assert jump["momentum_closure_piston"] < 0.15
    assert s["energy"]["balance_error_max"] < 0.02
    assert comp["final"] >= 0.5 * comp["peak"] > 0.0
    assert s["shocked"]["momentum_ahead"] >= 0.0
    # The wave reflected at the anvil is a reshock of the compacted bed: no less than every
    # pore closing needs, no more than keeping them (with a tenth for strength and ringing)
    r = s["reshock"]
    assert r["kept"] is True and r["sigma"] >= r["sigma_min"]
    assert r["sigma"] < 1.1 * r["sigma_pores_kept"]
    p1 = pdfem(["run", "s.toml", "-o", "one.h5", "--quiet"], tmp_path, ranks=1)
    assert p1.returncode == 0, p1.stderr
    a, b = datasets(tmp_path / "shock.h5"), datasets(tmp_path / "one.h5")
    assert sorted(a) == sorted(b) and "gauges/hammer/force" in a
    for k in a:
        assert np.array_equal(a[k], b[k]), f"{k} differs on 1 rank"


# [prepare] keys changed (None: no [prepare] table) and the error
BAD_PREPARE = {
    "no prepare table": (None, "prepare: the scene has no [prepare] table"),
    "unknown weight": ({"weight": "anvil"}, "prepare.weight: unknown block"),
    "too many grains": ({"grains": 500}, "prepare.grains: 500 grains need"),
    "reversed range": ({"semi_axis": [2.0e-4, 1.0e-4]}, "prepare.semi_axis: min must be <= max"),
}


@pytest.mark.parametrize("case", sorted(BAD_PREPARE))
def test_bad_preparation_input(tmp_path, case):
    change, msg = BAD_PREPARE[case]
    doc = prep_scene(grains=8)
    if change is None:
        del doc["prepare"]
    else:
        assert set(change) <= set(doc["prepare"])
        doc["prepare"].update(change)
    write_scene(tmp_path / "p.toml", doc)
    (tmp_path / "keep.h5").write_bytes(b"precious")
    p = pdfem(["prepare", "p.toml", "-o", "keep.h5", "--force"], tmp_path)
    assert p.returncode == 2, p.stderr
    assert msg in p.stderr and len(p.stderr.strip().splitlines()) == 1, p.stderr
    assert (tmp_path / "keep.h5").read_bytes() == b"precious"


GEOMETRIC_BAD = {
    "no packing": ({"packing": None}, "prepare.packing: required key missing (method "
                   "\"geometric\")"),
    "too high": ({"height": 5.0e-3}, "prepare.height: the bed would reach y = 0.0052 m, above "
                 "the domain box"),
    "packing out of range": ({"packing": 1.2}, "prepare.packing: must be in (0, 1)"),
}


@pytest.mark.parametrize("case", sorted(GEOMETRIC_BAD))
def test_bad_geometric_preparation_input(tmp_path, case):
    change, msg = GEOMETRIC_BAD[case]
    doc = small_prepare()
    for key, val in change.items():
        if val is None:
            doc["prepare"].pop(key)
        else:
            doc["prepare"][key] = val
    write_scene(tmp_path / "p.toml", doc)
    (tmp_path / "bed.h5").write_bytes(b"precious")
    p = pdfem(["prepare", "p.toml", "--force"], tmp_path)
    lines = p.stderr.strip().splitlines()
    assert p.returncode == 2 and len(lines) == 1 and msg in lines[0], p.stderr
    assert (tmp_path / "bed.h5").read_bytes() == b"precious"


def test_prepare_never_overwrites_without_force(tmp_path):
    write_scene(tmp_path / "p.toml", prep_scene(grains=8))
    (tmp_path / "bed.h5").write_bytes(b"precious")
    p = pdfem(["prepare", "p.toml"], tmp_path)
    assert p.returncode == 2 and "prepare.output" in p.stderr and "exists" in p.stderr
    assert (tmp_path / "bed.h5").read_bytes() == b"precious"


def test_sweep_on_2_ranks(small_bed, tmp_path):
    """Two piston speeds and the static compression on a bed 1 mm deep: the harder blow
    drives a faster front at a higher stress and density; rows carry the snowplow bound;
    the static curve rises to the grains' density. Between side walls: this bed's largest
    grains make the contact cells 0.34 mm, and periodic sides need 3 across the 1 mm box."""
    from pdfem.tools.study.speeds import walls_doc

    doc = walls_doc(small_shock(small_bed))
    write_scene(tmp_path / "p.toml", small_prepare(height=1.0e-3))
    p = pdfem(["prepare", "p.toml", "-o", "thin.h5"], tmp_path)
    assert p.returncode == 0, p.stderr
    doc["grains_file"]["path"] = str(tmp_path / "thin.h5")
    doc["domain"]["box"][3] = 2.8e-3
    doc["blocks"][1]["box"] = [0.0, 1.2e-3, 1.0e-3, 2.7e-3]
    write_scene(tmp_path / "s.toml", doc)
    p = pdfem(["sweep", "s.toml", "--velocities", "250,500", "--static", "-p", "sw"], tmp_path,
              ranks=2)
    assert p.returncode == 0, p.stderr
    body = json.loads((tmp_path / "sw.json").read_text())
    pts = body["points"]
    assert [q["velocity"] for q in pts] == [250.0, 500.0]
    assert all(q["sigma_source"] == "piston force" for q in pts)
    assert pts[1]["us_fit"] > pts[0]["us_fit"] > 0 and pts[1]["sigma"] > pts[0]["sigma"] > 0
    assert pts[1]["rho1"] > pts[0]["rho1"]
    assert all(q["snowplow_us"] > 0 and q["bound_kept"] for q in pts)
    assert all(q["us_min"] <= q["us"] and q["rho1"] <= q["rho1_max"] for q in pts)
    st = body["static"]
    assert max(st["density"]) > 1900.0 and max(st["sigma_piston"]) > 1.0e8
    assert st["floor"] < 2.0e7 and st["kinetic_over_work"] < 0.1
    assert 0.7 * 1900.0 < st["jamming_density"] < 1900.0
    assert (tmp_path / "sw.png").read_bytes()[:4] == b"\x89PNG"
    # A run analysed again with the sweep's JSON read for its jump-state figure (the scene
    # asks for no figures; tests/test_shock_analysis.py draws one)
    p = pdfem(["analyse", "sw-v500.h5", "-p", "an", "--sweep", "sw.json"], tmp_path)
    assert p.returncode == 0, p.stderr
    assert json.loads((tmp_path / "an-summary.json").read_text())["front"]["us"] == pts[1]["us"]


@pytest.mark.parametrize("args,msg", [
    (["sweep", "s.toml", "--velocities", "fast"], "--velocities: not a list of numbers"),
    (["sweep", "s.toml", "--velocities=0,-5"], "--velocities: need speeds > 0"),
    (["analyse", "missing.h5"], "missing.h5: no such run file"),
])
def test_bad_sweep_and_analyse_input(tmp_path, args, msg):
    write_scene(tmp_path / "s.toml", shock_scene("bed.h5", 1.0e-3))
    p = pdfem(args, tmp_path)
    assert p.returncode == 2 and msg in p.stderr, p.stderr
    assert len(p.stderr.strip().splitlines()) == 1


def test_sweep_marks_a_stopped_run_and_goes_on(small_bed, tmp_path):
    """Every speed whose run fails a guard (here an energy drift limit no run can meet) is a
    marked row with the guard's message, the sweep goes on to the next speed, writes its table
    and plot and exits 3; ``--level 1`` meshes the grains with the bed file's 6 quads."""
    doc = small_shock(small_bed)
    doc["guards"] = {"energy_drift": 1.0e-12}
    write_scene(tmp_path / "s.toml", doc)
    p = pdfem(["sweep", "s.toml", "--velocities", "250,500", "--level", "1", "-p", "sw"],
              tmp_path, ranks=2)
    assert p.returncode == 3, p.stderr
    assert "2 of 2 runs stopped on a guard" in p.stderr
    pts = json.loads((tmp_path / "sw.json").read_text())["points"]
    assert [q["velocity"] for q in pts] == [250.0, 500.0]
    assert all(q["us"] is None and "check energy drift" in q["stopped"] for q in pts)
    assert all(q["snowplow_us"] > 0 for q in pts)
    assert (tmp_path / "sw.png").read_bytes()[:4] == b"\x89PNG"
    with h5py.File(tmp_path / "sw-v250.h5.part") as f:
        kind, body = f["mesh/body_kind"][:], f["mesh/elem_body"][:]
    per_grain = np.bincount(body, minlength=kind.size)[kind == 0]
    assert per_grain.size > 0 and np.all(per_grain == 6)


def test_sweep_refuses_a_bad_level(small_bed, tmp_path):
    """A grain mesh level out of range: one line, exit 2, nothing written."""
    write_scene(tmp_path / "s.toml", small_shock(small_bed))
    for level in ("0", "17"):
        msg = "--level: need a grain mesh level from 1 to 16"
        p = pdfem(["sweep", "s.toml", "--level", level], tmp_path)
        assert p.returncode == 2 and msg in p.stderr, p.stderr
        assert len(p.stderr.strip().splitlines()) == 1
    assert not list(tmp_path.glob("sweep*"))


def test_sweep_stopped_by_sigterm_names_the_checkpoint(small_bed, tmp_path):
    """SIGTERM during a speed's run: the run writes its checkpoint, the sweep says where it is,
    starts no further speed, writes no table and exits 3 (it used to go on to analyse the
    unfinished run file and end on "cannot read the run file")."""
    write_scene(tmp_path / "s.toml", small_shock(small_bed))
    code, out, err = sigterm_when(["sweep", "s.toml", "--velocities", "250,500", "--level", "1",
                                   "-p", "sw"], tmp_path, tmp_path / "sw-v250.h5.part")
    assert code == 3, err
    assert "its checkpoint is sw-v250.h5.ckpt.h5" in out
    assert (tmp_path / "sw-v250.h5.ckpt.h5").is_file()
    assert "the speeds after it were not run" in out and "cannot read" not in out + err
    assert not list(tmp_path.glob("sw-v500*")) and not (tmp_path / "sw.json").exists()
