"""``pdfem study``: a tiny accuracy study on 2 ranks through the real command line, the
convergence study, and bad input (one line, exit status 2)."""

import csv
import json
import re

import pytest

from tests.helpers import pdfem, sigterm_when
from tests.scenes import drifting_grains, write_scene

COLUMNS = ["run", "axis", "level", "quads_per_grain", "rule", "safety", "kn0_scale", "wall_s",
           "steps", "us", "arrival", "hammer_stress", "packing", "us_se", "err_us", "err_arrival",
           "err_hammer_stress", "err_packing", "err_max", "pareto", "status", "run_file"]


def test_tiny_accuracy_study_on_2_ranks(tmp_path):
    # The packaged small shot-912 scene (the default), levels 1 and 2 only
    args = ["study", "accuracy", "--levels", "1,2", "--rules", "1pt,2x2", "--safety",
            "0.5,0.9", "--kn0-scale", "1", "-p", "acc"]
    p = pdfem(args, tmp_path, ranks=2)
    assert p.returncode == 0, p.stderr
    rows = list(csv.DictReader((tmp_path / "acc.csv").open()))
    assert list(rows[0]) == COLUMNS
    # The level x rule grid at the scene's safety factor, then the safety 0.9 at the baseline
    assert [(r["run"], r["axis"]) for r in rows[:4]] == [
        ("L1-1pt-s0.5-k1", "grid"), ("L1-2x2-s0.5-k1", "grid"), ("L2-1pt-s0.5-k1", "grid"),
        ("L2-2x2-s0.5-k1", "grid")]
    assert [r["axis"] for r in rows[4:]] == ["safety"] and rows[4]["safety"] == "0.9"
    for r in rows:
        assert float(r["wall_s"]) > 0 and r["status"] == "ok" and float(r["us_se"]) > 0
        assert (tmp_path / r["run_file"]).is_file()
    # The converged estimate: each rule's two levels extrapolated at order 2, then combined;
    # every error is against the combined value
    body = json.loads((tmp_path / "acc.json").read_text())
    assert body["provenance"]["ranks"] == 2
    assert body["scene"].endswith("shot912_small.toml") and body["speed"] is None
    est = body["estimate"]["us"]
    for rule, (coarse, fine) in (("1pt", rows[0:3:2]), ("2x2", rows[1:4:2])):
        q1, q2 = float(coarse["us"]), float(fine["us"])
        e = est["rules"][rule]
        assert e["how"] == "two levels, order 2 assumed" and e["levels"] == [1, 2]
        assert e["value"] == pytest.approx(q2 + (q2 - q1) / 3.0, rel=1e-5)
    us = est["combined"]["value"]
    assert min(e["value"] for e in est["rules"].values()) - 1e-6 <= us
    assert us <= max(e["value"] for e in est["rules"].values()) + 1e-6
    for r in rows:
        assert float(r["err_us"]) == pytest.approx(abs(float(r["us"]) - us) / us, rel=1e-4,
                                                   abs=1e-6)
    assert "converged estimate (Richardson extrapolation of each rule's levels):" in p.stdout
    assert re.search(r"front speed Us: \d+(\.\d+)? \+- [\d.e+]+ m/s", p.stdout)
    # Figure, table, recommendation, convergence orders
    assert (tmp_path / "acc.png").read_bytes()[:4] == b"\x89PNG"
    assert "| run | quads/grain | rule |" in p.stdout
    within = [r for r in rows if float(r["err_max"]) <= 0.05]
    assert ("for a 5 % answer choose level" in p.stdout) == bool(within)
    assert ("no run of the study has every error <= 5 %" in p.stdout) == (not within)
    assert re.search(r"observed order in h \(finest pair\): 1pt \d\.\d\d, 2x2 \d\.\d\d",
                     p.stdout)
    # No overwriting without --force
    again = pdfem(args + ["--no-convergence"], tmp_path)
    assert again.returncode == 2 and len(again.stderr.strip().splitlines()) == 1
    assert "--prefix: acc.csv exists" in again.stderr


def test_width_study_on_2_ranks(tmp_path):
    """Two seeds of the packaged bed 4 grains wide (1 mm): a row per bed with its front
    speed, the table and the seeds' spread printed; nothing overwritten without --force."""
    args = ["study", "width", "--widths", "4", "--seeds", "2", "--seed-width", "4", "-p", "w"]
    p = pdfem(args, tmp_path, ranks=2)
    assert p.returncode == 0, p.stderr
    body = json.loads((tmp_path / "w.json").read_text())
    rows = body["rows"]
    assert [(r["grains_wide"], r["seed"]) for r in rows] == [(4.0, 912), (4.0, 913)]
    for r in rows:
        assert r["width"] == pytest.approx(1.0e-3) and r["grains"] > 40
        assert r["us_fit"] > 0 and r["arrival_gauge"] > 0
        assert abs(r["rho0"] - 1235.0) < 0.02 * 1240.0
    assert body["conclusions"][0].startswith("4 grains wide: Us")
    assert "Us m/s" in p.stdout
    again = pdfem(args, tmp_path)
    assert again.returncode == 2 and "--prefix: w.json exists" in again.stderr


def test_convergence_study_prints_orders(tmp_path):
    p = pdfem(["study", "convergence", "--sizes", "4,8"], tmp_path)
    assert p.returncode == 0, p.stderr
    orders = re.search(r"1pt (\d\.\d\d), 2x2 (\d\.\d\d) \(expected 2\)", p.stdout)
    assert orders and all(1.7 < float(o) < 2.3 for o in orders.groups())


BAD = {
    "missing scene": (["nowhere.toml"], "nowhere.toml: cannot read the scene file"),
    "no shock table": (["plain.toml"], "needs a scene with a [shock] table"),
    "bad level list": (["--levels", "1,x"], "--levels: not a list of integers"),
    "level out of range": (["--levels", "0,2"], "--levels: 0 is not a level in [1, 10]"),
    "bad rule": (["--rules", "3x3"], "--rules: expected 1pt and/or 2x2"),
    "bad safety": (["--safety", "0.5,1.5"], "--safety: 1.5 is not a safety factor"),
    "bad stiffness": (["--kn0-scale", "0,1"], "--kn0-scale: 0.0 is not a factor > 0"),
    "bad baseline": (["--baseline", "2"], "--baseline: expected auto or LEVEL,RULE"),
    "bad tol": (["--tol", "5"], "--tol: must be in (0, 1)"),
    "no study": (None, "the following arguments are required: STUDY"),
}


@pytest.mark.parametrize("case", sorted(BAD))
def test_bad_study_input(tmp_path, case):
    extra, msg = BAD[case]
    write_scene(tmp_path / "plain.toml", drifting_grains(n=2, end=1e-7))
    args = ["study"] if extra is None else ["study", "accuracy"] + extra
    p = pdfem(args, tmp_path)
    assert p.returncode == 2, p.stderr
    assert msg in p.stderr and len(p.stderr.strip().splitlines()) == 1, p.stderr
    assert not (tmp_path / "study-accuracy-runs").exists()


def test_speeds_study_on_2_ranks(tmp_path):
    """The small bed's piston at 1500 m/s, level 1, 1-point rule, through the command on 2
    ranks: the rung runs to the scene's end, its row holds the answer and its checks, and the
    run file is the one `pdfem run` makes of the same scene on 1 rank."""
    import numpy as np

    from pdfem.tools.study.speeds import packaged_doc, rung_doc
    from tests.helpers import datasets

    p = pdfem(["study", "speeds", "--rule", "1pt", "--levels", "1", "--speeds", "1500"],
              tmp_path, ranks=2)
    assert p.returncode == 0, p.stderr
    body = json.loads((tmp_path / "study-speeds.json").read_text())
    rows = body["rows"]
    assert len(rows) == 1 and rows[0]["runs"] and rows[0]["velocity"] == 1500.0
    # Where the rows came from: the ranks and the machine line beside them
    prov = body["provenance"]
    assert prov["ranks"] == 2 and prov["machine"].endswith("2 rank(s)") and "UTC" in prov["date"]
    r = rows[0]
    # Measured 2026-12-06 (commit a820b7d, the points hourglass stiffness): Us 3429.2 m/s,
    # 0.11 % balance error, 0.21 % of the area folded (2.7 % with the coefficient spring)
    assert r["energy_error"] < 0.01 and 3000.0 < r["us"] < 3600.0 and 0.0 < r["folded"] < 0.01
    assert r["rho1_max"] > 1900.0 and r["us_min"] > 0.0 and isinstance(r["bound_kept"], bool)
    # Level 1's quads all touch their grain's boundary: no interior element to pass into
    assert r["interpenetrated"] == 0.0
    # Nothing passes the anvil or the hammer at level 1: the deepest excursion is contact
    # overlap (12.9 um below the anvil's face, measured at 4f2291a)
    assert not r["escaped"] and r["escape"] < 3.0e-5
    assert "small    1pt      1     1500  runs" in p.stdout
    write_scene(tmp_path / "one.toml", rung_doc(packaged_doc("small"), 1500.0, "1pt", 1))
    one = pdfem(["run", "one.toml", "-o", "one.h5", "--quiet"], tmp_path)
    assert one.returncode == 0, one.stderr
    a = datasets(tmp_path / "one.h5")
    b = datasets(tmp_path / "study-speeds-runs" / "small-1pt-l1-v1500.h5")
    assert a.keys() == b.keys() and all(np.array_equal(a[k], b[k]) for k in a)


def test_speeds_study_stopped_by_sigterm_names_the_checkpoint(tmp_path):
    """SIGTERM during a rung: the run writes its checkpoint, the study says so and where it
    is, starts no further rung and exits 3 (it used to go on to analyse the unfinished run
    file and end on "cannot read the run file")."""

    part = tmp_path / "study-speeds-runs" / "small-1pt-l1-v1500.h5.part"
    code, out, err = sigterm_when(["study", "speeds", "--rule", "1pt", "--levels", "1",
                                   "--speeds", "1500,2000"], tmp_path, part)
    assert code == 3, err
    ckpt = "study-speeds-runs/small-1pt-l1-v1500.h5.ckpt.h5"
    assert (tmp_path / ckpt).is_file() and f"its checkpoint is {ckpt}" in out
    assert "the rungs after it were not run" in out and "cannot read" not in out + err
    assert not list((tmp_path / "study-speeds-runs").glob("small-1pt-l1-v2000*"))
    rows = json.loads((tmp_path / "study-speeds.json").read_text())["rows"]
    assert len(rows) == 1 and not rows[0]["runs"] and "stopped by a signal" in rows[0]["stopped"]


@pytest.mark.parametrize("extra,msg", [
    (["--speeds", "0,500"], "--speeds: 0.0 is not a speed in (0, 1e5) m/s"),
    (["--levels", "11"], "--levels: 11 is not a level in [1, 10]"),
    (["--rule", "3x3"], "invalid choice: '3x3'"),
])
def test_bad_speeds_input(tmp_path, extra, msg):
    p = pdfem(["study", "speeds"] + extra, tmp_path)
    assert p.returncode == 2 and msg in p.stderr, p.stderr
    assert len(p.stderr.strip().splitlines()) == 1, p.stderr
    assert not (tmp_path / "study-speeds-runs").exists()
