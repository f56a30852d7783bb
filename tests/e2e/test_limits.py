"""Absurd-but-valid work is refused up front, through the real command line.

prepare (a bed of too many grains or sweeps, a rain phase of too many steps), sweep and study
accuracy (any run of the plan over 1e9 steps) and study width (any bed beyond the preparation's
limits): exit status 2, one stderr line naming the file, the key or option and the estimate,
the folder exactly as it was, before the first run starts. --allow-huge skips the refusal.
"""

import contextlib
import io
import os
import signal
import subprocess
import sys
from importlib import resources

import pytest

from pdfem.cli import main
from pdfem.scene.toml_out import dumps
from tests.e2e.test_bad_input import _state
from tests.helpers import ROOT
from tests.scenes import packaged, prep_scene, small_prepare


def _wide_bed(width, height):
    """The small geometric preparation with a bed ``width`` wide and ``height`` high."""
    doc = small_prepare("bed.h5", height=height)
    doc["domain"]["box"] = [0.0, 0.0, width, height + 2.0e-4]
    doc["blocks"][0]["box"] = [0.0, 0.0, width, 2.0e-4]
    return dumps(doc)


SCENES = resources.files("pdfem") / "scenes"
SMALL = str(SCENES / "shot912_small.toml")
# Input files, and the line each command is refused with (the hard caps of pdfem.scene, which
# no option lifts, in HARD)
FILES = {
    "wide.toml": _wide_bed(1.0, 0.1),
    "sweeps.toml": dumps(small_prepare("bed.h5", sweeps=10**12)),
    "rain.toml": dumps(prep_scene(grains=20000)),
    "rain-long.toml": dumps(prep_scene(phase_time=1.0e3)),
    "rain-1e9.toml": dumps(prep_scene(grains=10**9)),
    "geo-1e9.toml": _wide_bed(100.0, 100.0),
}
REFUSED = {
    "prepare a bed of 1.4e6 grains": (
        ["prepare", "wide.toml"], "wide.toml: prepare.height: a bed 1 m wide and 0.1 m high "
        "at packing 0.65 holds about 1.37e+06 grains, more than 1e+06"),
    "prepare 1e12 sweeps": (["prepare", "sweeps.toml"], "sweeps.toml: prepare.sweeps: "
                            "1000000000000 sweeps of about 27.4 grains"),
    "prepare 20000 rained grains": (["prepare", "rain.toml"], "rain.toml: prepare.grains: "
                                    "20000 grains to rain, more than 1e+04"),
    "prepare a rain phase of 4e10 steps": (
        ["prepare", "rain-long.toml"], "rain-long.toml (rain phase): prepare.phase_time: "
        "about 3.86e+10 steps of"),
    "prepare 1e9 rained grains": (["prepare", "rain-1e9.toml"],
                                  "rain-1e9.toml: prepare.grains: must be <= 1e+07"),
    "prepare a bed of 1e9 grains": (["prepare", "geo-1e9.toml"], "geo-1e9.toml: prepare.height:"
                                    " a bed this size could hold"),
    "sweep with a piston at 1 um/s": (
        ["sweep", SMALL, "--velocities", "100,1e-6", "-p", "sw"],
        "shot912_small.toml (piston at 1e-06 m/s): --velocities: about 1.57e+12 steps"),
    "study accuracy at safety 1e-9": (
        ["study", "accuracy", "--levels", "1,2", "--safety", "1e-9,0.5", "-p", "acc"],
        "shot912_small.toml (L1-1pt-s1e-09-k1): time.end: about 1.88e+12 steps"),
    "study accuracy, an axis run at 1e12 x kn0": (
        ["study", "accuracy", "--levels", "1", "--rules", "1pt", "--safety", "0.5",
         "--kn0-scale", "1,1e12", "-p", "acc"],
        "shot912_small.toml (L1-1pt-s0.5-k1e+12): time.end: about"),
}
HARD = ("prepare 1e9 rained grains", "prepare a bed of 1e9 grains")


@pytest.fixture(scope="module")
def folder(tmp_path_factory):
    d = tmp_path_factory.mktemp("limits")
    for name, text in FILES.items():
        (d / name).write_text(text)
    return d


def _in_process(args, cwd):
    """``pdfem.cli.main(args)`` in the folder cwd: (exit status, stderr)."""
    err = io.StringIO()
    with contextlib.chdir(cwd), contextlib.redirect_stdout(io.StringIO()), \
            contextlib.redirect_stderr(err):
        return main(args), err.getvalue()


@pytest.mark.parametrize("case", sorted(REFUSED))
def test_absurd_work_is_refused_up_front(folder, case):
    args, text = REFUSED[case]
    before = _state(folder)
    status, err = _in_process(args, folder)
    lines = err.strip().splitlines()
    assert status == 2 and "Traceback" not in err, err
    assert len(lines) == 1 and lines[0].startswith("pdfem: error: ") and text in lines[0], \
        (text, err)
    assert ("pass --allow-huge if you mean it" in lines[0]) == (case not in HARD), lines[0]
    # Nothing written: no bed, no run of an earlier speed or setting, no runs folder
    assert _state(folder) == before and not (folder / "acc-runs").exists()


def test_allow_huge_skips_the_bed_size_check(folder, tmp_path):
    """20000 rained grains pass the size check with --allow-huge; the chamber's own check
    (they do not fit) then refuses them, still before anything is written."""
    (tmp_path / "rain.toml").write_text(FILES["rain.toml"])
    status, err = _in_process(["prepare", "rain.toml", "--allow-huge"], tmp_path)
    lines = err.strip().splitlines()
    assert status == 2 and len(lines) == 1, err
    assert "prepare.grains: 20000 grains need" in lines[0] and "more than the domain" in lines[0]
    assert sorted(os.listdir(tmp_path)) == ["rain.toml"]


def _started(args, cwd, line_start):
    """Start ``python -m pdfem args``; True once a stdout line starts with ``line_start``
    (the work began: the refusal was skipped); the process is then killed."""
    env = dict(os.environ, PYTHONPATH=str(ROOT))
    p = subprocess.Popen([sys.executable, "-m", "pdfem"] + args, cwd=cwd, env=env, text=True,
                         stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    try:
        return any(line.startswith(line_start) for line in p.stdout)
    finally:
        p.send_signal(signal.SIGKILL)
        p.communicate(timeout=60)


def test_allow_huge_starts_the_sweep(tmp_path):
    assert _started(["sweep", SMALL, "--velocities", "1e-6", "-p", "sw", "--allow-huge"],
                    tmp_path, "pdfem sweep: piston at 1e-06 m/s")


def test_allow_huge_starts_the_accuracy_study(tmp_path):
    assert _started(["study", "accuracy", "--levels", "1", "--rules", "1pt", "--safety",
                     "1e-9", "-p", "acc", "--allow-huge"], tmp_path, "pdfem study accuracy:")


def test_width_study_refuses_a_bed_beyond_the_limit_before_preparing(tmp_path, monkeypatch):
    """The study's every bed is checked before the first is prepared (the limit lowered to
    100 grains: the default 1e6 is beyond the study's widest bed, 4096 grains wide)."""
    from pdfem.prepare import size

    monkeypatch.setattr(size, "MAX_GEOMETRIC_GRAINS", 100)
    status, err = _in_process(["study", "width", "--widths", "4,8", "--seeds", "1"], tmp_path)
    lines = err.strip().splitlines()
    assert status == 2 and len(lines) == 1, err
    assert "shot912_prepare.toml (w8-s912): prepare.height: a bed 0.002 m wide" in lines[0]
    assert "more than 1e+02" in lines[0]
    assert os.listdir(tmp_path) == []


def test_the_packaged_preparations_are_within_the_limits():
    """The estimate of the packaged beds is their grain count within 6 %, far below the
    limits (they prepare unchanged: tests/test_fuzz_commands.py prepares the small one)."""
    import h5py

    from pdfem.prepare.size import MAX_GEOMETRIC_GRAINS, check_size
    from pdfem.scene import load_scene

    for name in ("shot912", "shot912_small"):
        n = check_size(load_scene(SCENES / f"{name}_prepare.toml").resolved, name)
        with h5py.File(SCENES / f"{name}_bed.h5") as f:
            made = f["grains/x"].shape[0]
        assert abs(n - made) <= 0.06 * made and n < MAX_GEOMETRIC_GRAINS / 1000, (name, n, made)


def _long():
    """The small shot-912 scene run for 1000 s (about 4e12 steps), its outputs scaled with it
    (the packaged intervals would imply more frames than a run may hold)."""
    doc = packaged("shot912_small.toml")
    doc["time"]["end"] = 1.0e3
    doc["output"].update(interval=50.0, energy_interval=5.0, gauge_interval=0.5)
    return doc


def test_check_runs_builds_nothing_with_allow_huge():
    """--allow-huge passes a plan whose runs would be refused without it."""
    from pdfem.errors import InputError
    from pdfem.limits import check_runs
    from pdfem.parallel.mpi import world
    from pdfem.scene import parse_scene

    scene = parse_scene(_long(), name="long")
    with pytest.raises(InputError, match="long: time.end: about"):
        check_runs([(scene, "long")], world())
    check_runs([(scene, "long")], world(), allow_huge=True)


def test_check_runs_passes_over_a_run_whose_set_up_stops_on_a_guard():
    """time.dt_min above the stable step stops the set-up (SimulationError): the check leaves
    that run to the command, which stops it on its turn as before; the next run is checked."""
    from pdfem.errors import InputError, SimulationError
    from pdfem.limits import check_runs
    from pdfem.parallel.mpi import world
    from pdfem.scene import parse_scene
    from pdfem.solver import Simulation

    doc = packaged("shot912_small.toml")
    doc["time"].update(dt_min=1.0e-6, dt_max=1.0e-5)
    stops = parse_scene(doc, name="stops")
    with pytest.raises(SimulationError, match="below time.dt_min"):
        Simulation(stops, world())
    with pytest.raises(InputError, match="long: time.end: about"):
        check_runs([(stops, "stops"), (parse_scene(_long(), name="long"), "long")], world())
