"""The hard-case suite at CI size: ``mpirun -n 2 python -m pdfem study hard --size ci`` per
case. Each must run to completion on 1 and on 2 ranks with the energy balance within 2 %,
every frame finite, no integration-point Jacobian <= 0, and bit-identical run files."""

import json

import pytest

from pdfem.tools.study.hard import ENERGY_TOL
from pdfem.tools.study.hard_cases import CASES, LARGE_ONLY
from tests.helpers import pdfem

CI_CASES = [c for c in CASES if c not in LARGE_ONLY]


@pytest.mark.parametrize("case", CI_CASES)
def test_hard_case(tmp_path, case):
    p = pdfem(["study", "hard", "--size", "ci", "--case", case, "-p", "h"], tmp_path, ranks=2,
              timeout=600)
    assert p.returncode == 0, p.stderr
    row = json.loads((tmp_path / "h.json").read_text())[0]
    assert row["status"] == "ok", row["status"]
    assert row["energy_error"] <= ENERGY_TOL, row
    assert row["finite"] and row["jacobian_min"] > 0, row
    assert row["identical"], row
    assert row["passed"]


def test_study_hard_bad_input(tmp_path):
    # One rank cannot compare 1 with N ranks; an unknown case; a large-only case at CI size
    p = pdfem(["study", "hard", "--size", "ci"], tmp_path)
    assert p.returncode == 2 and "under mpirun with 2 or more ranks" in p.stderr
    for case in ("bogus", "settle-1e6"):
        p = pdfem(["study", "hard", "--size", "ci", "--case", case], tmp_path, ranks=2)
        lines = p.stderr.strip().splitlines()
        assert p.returncode == 2 and len(lines) == 1 and f"--case: {case!r}" in lines[0], p.stderr
    assert not list(tmp_path.iterdir())


def test_ladders_are_named_rungs_of_valid_scenes():
    """Each rung of the speed and refinement ladders is the small bed's piston at its speed
    and level with the EOS and the potential law, a valid scene; the ladders run only by name
    and only at the large size."""
    from pdfem.scene import parse_scene
    from pdfem.tools.study.hard_cases import LADDER_CASES, LADDERS

    rungs = {r for v in LADDERS.values() for r in v}
    assert rungs == set(LADDER_CASES) and rungs <= set(LARGE_ONLY)
    for name in rungs:
        doc = CASES[name][0](None, "large")
        speed = -doc["bc"][-1]["velocity"][1]
        level = doc["element"]["level"]
        assert name in (f"speed-{speed:g}", f"refine-{speed:g}-l{level}")
        assert name.startswith("refine") or level == 2
        assert doc["contact"]["law"] == "potential"
        assert doc["materials"]["hmx"]["eos"] == "us_up"
        parse_scene(doc, name=name)


def test_a_ladder_is_refused_at_ci_size(tmp_path):
    p = pdfem(["study", "hard", "--size", "ci", "--case", "speeds"], tmp_path, ranks=2)
    assert p.returncode == 2 and "'speed-100' is not a case of --size ci" in p.stderr, p.stderr
