"""``pdfem study hotspots``: the thermal variant of a short piston shot at levels 1 and 2
through the real command line, and its bad input."""

import csv
import json

import h5py
import numpy as np
import pytest

from pdfem.effects.heat import MECHANISMS
from pdfem.tools.study.hotspots import thermal_variant
from tests.helpers import pdfem
from tests.scenes import drifting_grains, packaged, write_scene

# The heat-by-mechanism frame fields
HEAT_FIELDS = tuple(f"heat_{m}" for m in MECHANISMS)


def short_shot(tmp_path, end=3.0e-7):
    """The packaged small piston shot (isothermal) cut to ``end``."""
    doc = packaged("shot912_small.toml")
    doc["time"]["end"] = end
    doc["output"]["interval"] = end / 3
    return write_scene(tmp_path / "short.toml", doc)


def test_hotspot_study_at_two_levels(tmp_path):
    short_shot(tmp_path)
    args = ["study", "hotspots", "short.toml", "--levels", "1,2", "--thresholds", "300,320",
            "-p", "hs"]
    p = pdfem(args, tmp_path)
    assert p.returncode == 0, p.stderr
    rows = list(csv.DictReader((tmp_path / "hs.csv").open()))
    body = json.loads((tmp_path / "hs.json").read_text())
    assert [(r["level"], r["quads_per_grain"], r["status"]) for r in rows] == [
        ("1", "6", "ok"), ("2", "24", "ok")]
    runs = sorted((tmp_path / "hs-runs").glob("L*.h5"))
    assert [r.name for r in runs] == ["L1-2x2-s0.5-k1.h5", "L2-2x2-s0.5-k1.h5"]
    for row, jrow, run in zip(rows, body["rows"], runs, strict=True):
        with h5py.File(run) as f:
            effects = f.attrs["effects"].split(",")
            grain = f["mesh/body_kind"][()][f["mesh/elem_body"][()]] == 0
            # The run is the thermal variant (the crystal on its Hugoniot: no thermo-elastic
            # coupling) and its grains are meshed at the row's level
            assert {"heat", "viscous_heating", "friction_heating"} <= set(effects)
            assert "thermoelastic" not in effects
            ngrain = int(np.sum(f["mesh/body_kind"][()] == 0))
            assert grain.sum() == ngrain * int(row["quads_per_grain"])
            # The heat by mechanism is the grains' sum of the last frame's fields
            for name in HEAT_FIELDS:
                want = f[f"frames/{name}"][-1][grain].sum()
                assert float(row[name]) == pytest.approx(want, rel=1e-5, abs=1e-9)
            t = f["frames/element_temperature"][-1][grain]
        # The peak behind the front is at most the hottest grain element, the rise positive
        assert jrow["max"] <= t.max() + 1e-9 and jrow["max"] > jrow["t_initial"]
        assert jrow["mean"] <= jrow["p99"] <= jrow["p99.9"] <= jrow["max"]
    # The change of the rise between the two levels, from the rows
    a, b = body["rows"]
    (chg,) = body["changes"]
    assert chg["levels"] == [1, 2]
    for key in ("mean", "p99", "p99.9", "max"):
        assert chg[key] == pytest.approx((b[key] - a[key]) / (b[key] - b["t_initial"]))
    assert "change of the temperature rise between levels" in p.stdout
    # No overwriting without --force
    again = pdfem(args, tmp_path)
    assert again.returncode == 2 and "--prefix: hs.csv exists" in again.stderr


def test_thermal_variant_switches_on_what_the_scene_can_have():
    doc = packaged("shot912_small.toml")
    doc["output"]["fields"] = ["x", "v"]
    hot = thermal_variant(doc)
    assert {"heat", "conduction", "dissipation_heating", "viscous_heating",
            "friction_heating"} <= set(hot)
    assert hot["output"]["fields"] == ["x", "v", "element_temperature", *HEAT_FIELDS]
    assert "heat" not in doc
    # The thermo-elastic coupling only where every material's bulk is linear (the packaged
    # crystal is on its Hugoniot)
    assert "thermoelastic" not in hot and "thermal_expansion" not in hot
    for key in ("eos", "eos_s"):
        doc["materials"]["hmx"].pop(key)
    assert {"thermoelastic", "thermal_expansion"} <= set(thermal_variant(doc))
    # A scene with [heat] keeps its own heat effects
    doc = packaged("shot912_small.toml")
    doc["heat"] = {"initial": 250.0}
    assert thermal_variant(doc)["heat"] == {"initial": 250.0}
    assert "conduction" not in thermal_variant(doc)


BAD = {
    "no shock table": (["plain.toml"], "needs a scene with a [shock] table"),
    "bad rule": (["--rule", "3x3"], "--rule: expected 1pt or 2x2"),
    "bad thresholds": (["--thresholds", "400,-1"], "--thresholds: '-1' out of range"),
    "bad spot threshold": (["--spot-threshold", "nan"], "--spot-threshold: 'nan' out of range"),
    "bad levels": (["--levels", "0"], "--levels: 0 is not a level in [1, 10]"),
}


@pytest.mark.parametrize("case", sorted(BAD))
def test_bad_hotspot_study_input(tmp_path, case):
    extra, msg = BAD[case]
    write_scene(tmp_path / "plain.toml", drifting_grains(n=2, end=1e-7))
    p = pdfem(["study", "hotspots"] + extra, tmp_path)
    assert p.returncode == 2, p.stderr
    assert msg in p.stderr and len(p.stderr.strip().splitlines()) == 1, p.stderr
    assert not (tmp_path / "study-hotspots-runs").exists()


def test_a_thermal_shock_run_writes_its_census_with_the_summary(tmp_path):
    """pdfem run of a thermal shock scene: the analysis adds the hot-spot census files and
    the summary's hotspots part; analyse refuses to overwrite them without --force."""
    doc = thermal_variant(packaged("shot912_small.toml"))
    doc["time"]["end"] = 3.0e-7
    doc["output"].update(path="hot.h5", interval=1.0e-7)
    doc["shock"]["plots"] = "none"
    write_scene(tmp_path / "hot.toml", doc)
    p = pdfem(["run", "hot.toml"], tmp_path)
    assert p.returncode == 0, p.stderr
    assert "temperature behind the front at" in p.stdout
    summary = json.loads((tmp_path / "hot-summary.json").read_text())
    hs = summary["hotspots"]
    census = json.loads((tmp_path / "hot-hotspots.json").read_text())
    last = census["frames"][-1]["shocked"]
    assert hs["shocked"]["max"] == last["max"] and hs["shocked"]["p99"] == last["p99"]
    assert hs["heat_fields"] == list(HEAT_FIELDS)
    for suffix in ("-hotspots.csv", "-hotspots-spots.csv", "-hotspots-front.csv"):
        assert (tmp_path / f"hot{suffix}").is_file()
    again = pdfem(["analyse", "hot.h5", "-p", "hot"], tmp_path)
    assert again.returncode == 2 and "hot-summary.json exists" in again.stderr
    again = pdfem(["analyse", "hot.h5", "-p", "hot", "--force"], tmp_path)
    assert again.returncode == 0, again.stderr


def test_a_study_level_of_absurdly_many_steps_is_refused_up_front(tmp_path):
    """time.end a million times too long: refused before the first run, nothing written."""
    doc = packaged("shot912_small.toml")
    doc["time"]["end"] = 3.0
    # Outputs scaled with it (the packaged intervals would imply more frames than a run holds)
    doc["output"].update(interval=0.15, energy_interval=0.015, gauge_interval=0.0015)
    for bc in doc["bc"]:
        bc.pop("release", None)
        bc.pop("ramp_down", None)
    write_scene(tmp_path / "long.toml", doc)
    p = pdfem(["study", "hotspots", "long.toml", "--levels", "1"], tmp_path)
    assert p.returncode == 2, p.stderr
    assert "time.end: about" in p.stderr and "--allow-huge" in p.stderr, p.stderr
    assert len(p.stderr.strip().splitlines()) == 1
    assert not (tmp_path / "study-hotspots-runs").exists()
