"""The accuracy study's plan, contact scaling, errors, Pareto front and recommendation."""

import math

from pdfem.tools.study import accuracy as acc
from pdfem.tools.study.pareto import add_errors, mark_pareto, recommend, recommendation_line

KEYS = ("us", "arrival", "hammer_stress", "packing")


def test_plan_grid_and_axes():
    grid = acc.grid_settings([1, 2], ["1pt", "2x2"], 0.5)
    assert [s.label for s in grid] == ["L1-1pt-s0.5-k1", "L1-2x2-s0.5-k1", "L2-1pt-s0.5-k1",
                                       "L2-2x2-s0.5-k1"]
    axes = acc.axis_settings(grid[2], [0.25, 0.5, 0.9], [0.1, 1.0, 10.0])
    assert [(s.axis, s.safety, s.kn0_scale) for s in axes] == [
        ("safety", 0.25, 1.0), ("safety", 0.9, 1.0), ("kn0", 0.5, 0.1), ("kn0", 0.5, 10.0)]
    assert grid[3].quads == 24
    # A setting twice runs once, with its first reason
    again = acc.unique(grid + [acc.Setting(2, "2x2", 0.5, 1.0, "safety")])
    assert len(again) == 4 and again[3].axis == "grid"
    # Every setting a study may run: the grid, then the axes around each grid point
    every = acc.possible_settings([1, 2], ["2x2"], [0.5, 0.9], [1.0, 10.0], 0.5)
    assert [s.label for s in every] == ["L1-2x2-s0.5-k1", "L2-2x2-s0.5-k1", "L1-2x2-s0.9-k1",
                                        "L1-2x2-s0.5-k10", "L2-2x2-s0.9-k1", "L2-2x2-s0.5-k10"]


def test_scale_contact_scales_every_given_stiffness():
    doc = {"contact": {"kn0": 1e16, "delta_max": 3e-5,
                       "pairs": {"a:b": {"kn0": 2e16, "ks": 1e16}, "a:c": {"friction": 0.1}}}}
    acc.scale_contact(doc, 0.1)
    assert doc["contact"]["kn0"] == 1e15 and "ks" not in doc["contact"]
    assert doc["contact"]["delta_max"] == 3e-5
    assert doc["contact"]["pairs"]["a:b"] == {"kn0": 2e15, "ks": 1e15}
    assert doc["contact"]["pairs"]["a:c"] == {"friction": 0.1}


def _row(label, wall, vals, axis="grid"):
    lv, rule, s, k = label.split("-")
    st = acc.Setting(int(lv[1:]), rule, float(s[1:]), float(k[1:]), axis)
    return {"setting": st, "wall_s": wall, "steps": 1, "status": "ok", "run_file": "",
            **dict(zip(KEYS, vals, strict=True))}


def test_errors_pareto_and_the_choice():
    ref = dict(zip(KEYS, (1000.0, 1e-6, 3e8, 0.99), strict=True))
    rows = [_row("L3-2x2-s0.5-k1", 100.0, (1000.0, 1e-6, 3e8, 0.99)),  # exact, dearest
            _row("L1-1pt-s0.5-k1", 1.0, (600.0, 1e-6, 3e8, 0.99)),     # 40 % off, cheapest
            _row("L1-2x2-s0.5-k1", 2.0, (1030.0, 1e-6, 3e8, 0.99)),    # 3 %
            _row("L2-1pt-s0.5-k1", 3.0, (1040.0, 1e-6, 3e8, 0.99)),    # 4 %, dearer: off front
            _row("L2-2x2-s0.5-k1", 5.0, (1000.0, 1e-6, 2.97e8, 0.99)),  # 1 %
            _row("L2-2x2-s0.5-k10", 9.0, (math.nan, 1e-6, 3e8, 0.99))]  # no Us: never chosen
    add_errors(rows, ref)
    assert rows[0]["err_max"] == 0.0 and all(rows[0]["err_" + k] == 0.0 for k in KEYS)
    assert rows[2]["err_us"] == 0.03 and math.isinf(rows[5]["err_max"])
    mark_pareto(rows)
    assert [r["setting"].label for r in rows if r["pareto"]] == [
        "L3-2x2-s0.5-k1", "L1-1pt-s0.5-k1", "L1-2x2-s0.5-k1", "L2-2x2-s0.5-k1"]
    assert recommend(rows, 0.05)["setting"].label == "L1-2x2-s0.5-k1"
    assert recommend(rows, 0.02)["setting"].label == "L2-2x2-s0.5-k1"
    assert recommend(rows, 0.001)["setting"].label == "L3-2x2-s0.5-k1"
    line = recommendation_line(rows, 0.05)
    assert "choose level 1 (6 quads per grain), rule 2x2" in line
    assert "50 x faster than the dearest run of the study (L3-2x2-s0.5-k1, 100.0 s)" in line
    # The baseline of the axes: the cheapest grid run within the tolerance, else the closest
    assert acc.baseline(rows, 0.05).label == "L1-2x2-s0.5-k1"
    assert acc.baseline(rows, 0.001).label == "L3-2x2-s0.5-k1"
    rows[0]["err_max"] = 0.002
    assert recommend(rows, 0.001) is None
    assert acc.baseline(rows, 0.001).label == "L3-2x2-s0.5-k1"
    line = recommendation_line(rows, 0.001)
    assert line.startswith("no run of the study has every error <= 0.1 %")
    assert "the closest is level 3 (54 quads per grain), rule 2x2" in line


def test_speed_rungs_hold_the_piston_until_the_slowest_front_has_crossed():
    """study speeds' rungs: times scaled by 288/V, and from 500 m/s on the release moved so
    that the piston starts to slow only once the slowest front the bed allows (the sweep's
    bound, H0 / Us_min) has crossed; the end moves with it. At 288 m/s the packaged scene
    already holds it that long and the rung is the scaled scene unchanged."""
    from pdfem.scene import parse_scene
    from pdfem.tools.study import hugoniot as hg
    from pdfem.tools.study import speeds as sp

    doc = sp.packaged_doc("small")
    (bc0,) = [b for b in doc["bc"] if "release" in b]
    for v in (288.0, 2000.0):
        plain, held = sp.piston_doc(doc, v, "2x2", 1), sp.rung_doc(doc, v, "2x2", 1)
        (bp,), (bh,) = ([b for b in d["bc"] if "release" in b] for d in (plain, held))
        f = 288.0 / v
        assert bp["release"] == bc0["release"] * f and bp["ramp_down"] == bc0["ramp_down"] * f
        scene = parse_scene(plain, ".", name="rung")
        H0, phi0, _ = hg.bed_figures(scene)
        us = hg.slowest_front(v, 1900.0 * phi0, 1900.0, hg.grain_material(scene.resolved))
        assert math.isclose(sp.crossing_time(scene, v), H0 / us, rel_tol=1e-15)
        if v == 288.0:
            assert held == plain
            assert bp["release"] - bp["ramp_down"] >= H0 / us
            continue
        # 2 mm / 4063 m/s = 0.492 us, where the scaled release starts slowing at 0.372 us
        assert bp["release"] - bp["ramp_down"] < 0.8 * H0 / us
        assert math.isclose(bh["release"] - bh["ramp_down"], H0 / us, rel_tol=1e-12)
        assert bh["ramp_down"] == bp["ramp_down"]
        assert math.isclose(held["time"]["end"] - plain["time"]["end"],
                            bh["release"] - bp["release"], rel_tol=1e-12)
        held["bc"], plain["bc"] = None, None
        held["time"]["end"] = plain["time"]["end"]
        assert held == plain


def test_speed_rungs_sides_periodic_or_walls():
    """The packaged scenes have periodic sides; study speeds --sides walls puts them between
    frictionless walls with rollers (both scenes valid), and --sides periodic gives back the
    packaged scene unchanged."""
    from pdfem.scene import parse_scene
    from pdfem.tools.study import speeds as sp

    doc = sp.packaged_doc("small")
    assert doc["domain"]["periodic"] == "x" and "left" not in doc.get("walls", {})
    assert sp.periodic_doc(doc) == doc
    walled = sp.walls_doc(doc)
    assert "periodic" not in walled["domain"]
    assert walled["walls"]["left"] == walled["walls"]["right"] == "frictionless"
    assert [b for b in walled["bc"] if "wall" in b] == [
        {"wall": "left", "type": "roller"}, {"wall": "right", "type": "roller"}]
    assert sp.periodic_doc(walled) == {**doc, "walls": {}}
    for d in (walled, doc):
        assert parse_scene(sp.rung_doc(d, 1500.0, "2x2", 1), ".", name="rung").resolved


def test_accuracy_at_speed_scales_from_the_scenes_own_piston(tmp_path):
    """study accuracy --speed V: the packaged scene's piston at V, as study speeds builds its
    rung (the scene's times scaled from its own 288 m/s); the same scene written at 1000 m/s
    scales from 1000; a scene whose hammer is not driven is refused naming the key."""
    import tomllib
    from importlib import resources

    import pytest

    from pdfem.cli.study import _at_speed
    from pdfem.errors import InputError
    from pdfem.scene import load_scene, parse_scene
    from pdfem.tools.study import speeds as sp

    path = str(resources.files("pdfem") / "scenes" / "shot912_small.toml")
    with open(path, "rb") as fh:
        doc = tomllib.load(fh)
    scene = load_scene(path)
    fast, fast_scene = _at_speed(doc, scene, path, 1500.0)
    el = scene.resolved["element"]
    want = sp.rung_doc(sp.packaged_doc("small"), 1500.0, el["rule"], el["level"])
    want["grains_file"]["path"] = fast["grains_file"]["path"]
    assert fast == want
    assert str(fast_scene.path) == path
    assert fast_scene.resolved["time"]["end"] == fast["time"]["end"]
    # Written at 1000 m/s: going to 1500 scales by 1000/1500, not 288/1500
    at1000 = sp.piston_doc(doc, 1000.0, el["rule"], el["level"])
    again, _ = _at_speed(at1000, parse_scene(at1000, scene.base_dir, path=path), path, 1500.0)
    (b1,), (b2,) = ([b for b in d["bc"] if "release" in b] for d in (again, fast))
    for a, b in ((again["time"]["end"], fast["time"]["end"]), (b1["release"], b2["release"]),
                 (b1["ramp_down"], b2["ramp_down"])):
        assert math.isclose(a, b, rel_tol=1e-12)
    # No driven hammer
    free = {**doc, "bc": [b for b in doc["bc"] if b.get("type") != "velocity"]}
    with pytest.raises(InputError, match=r"shot912_small.toml: bc: --speed needs"):
        _at_speed(free, parse_scene(free, scene.base_dir, path=path), path, 1500.0)
    with pytest.raises(InputError, match=r"--speed: -1.0 is not a speed"):
        _at_speed(doc, scene, path, -1.0)
