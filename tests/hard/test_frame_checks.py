"""The hard-case verdict on a run file (pdfem.tools.study.hard.frame_checks) against hand-built
frames: a square, a dart whose reflex corner has a negative Jacobian while its centre and
Gauss points stay valid, and a non-finite frame."""

import h5py
import numpy as np
import pytest

from pdfem.tools.study.hard import frame_checks

SQUARE = [[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]]
# Corner 2 pushed past the diagonal 1-3: corner Jacobian (x3-x2)x(x1-x2)/4 = -0.05
DART = [[0.0, 0.0], [1.0, 0.0], [0.4, 0.4], [0.0, 1.0]]


def _run_file(path, frames, rule="1pt", err=(0.0, 0.01)):
    with h5py.File(path, "w") as f:
        f["mesh/conn"] = np.array([[0, 1, 2, 3]], np.int64)
        f["frames/x"] = np.array(frames, float)
        f["energy/balance_error"] = np.array(err)
        f.attrs["scene"] = f'[element]\nrule = "{rule}"\n'


@pytest.mark.parametrize("rule", ["1pt", "2x2"])
def test_dart_corner_folds_while_points_stay_valid(tmp_path, rule):
    p = tmp_path / "r.h5"
    _run_file(p, [SQUARE, DART], rule)
    c = frame_checks(p)
    # Centre Jacobian of the dart: area / 4 = 0.4 / 4; its reflex corner: -0.05
    assert c["corner_fold"] == pytest.approx(-0.05 / 0.1)
    assert c["folded"] == 1 and c["elements"] == 1
    assert c["jacobian_min"] > 0.0 and c["finite"]
    assert np.isnan(c["jacobian_ratio"]) and c["energy_error"] == 0.01


def test_square_frames_and_a_non_finite_one(tmp_path):
    p = tmp_path / "r.h5"
    _run_file(p, [SQUARE, SQUARE])
    c = frame_checks(p)
    assert c["corner_fold"] == pytest.approx(1.0) and c["folded"] == 0
    assert c["jacobian_min"] == pytest.approx(0.25) and c["jacobian_ratio"] == pytest.approx(1.0)
    bad = np.array([SQUARE, SQUARE], float)
    bad[1, 2, 0] = np.nan
    _run_file(p, bad)
    assert not frame_checks(p)["finite"]
