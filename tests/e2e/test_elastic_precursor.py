"""The default scene's HMX crystal (cap strength, Us-up equation of state) struck in uniaxial
strain below the speed at which its plastic wave overtakes the elastic one: two waves, the
elastic precursor at the Hugoniot elastic limit and the plastic wave behind it, each at the
speed and amplitude of its closed form."""

import math
from pathlib import Path

import numpy as np
import pytest

from tests.helpers import datasets, pdfem
from tests.scenes import crystal_column, packaged, write_scene

UP = 130.0  # piston [m/s]
HEIGHT = 3.0e-3  # column [m]


def _crystal():
    """The packaged scene's crystal, its parameters and the closed forms of the two waves.

    Uniaxial strain, compression positive (eta = 1 - V/V0): the deviatoric stress reaches the
    envelope sqrt(J2) = A (B = C = 0) at eta_Y = Y / 2G, Y = sqrt(3) A; the axial stress there
    is p_H(eta_Y) + 2Y/3 (the Hugoniot elastic limit). Each wave is a jump on its Rayleigh
    line, Lagrangian speed U = sqrt(d sigma / (rho0 d eta)), particle velocity jump U d eta.
    """
    m = dict(packaged("shot912.toml")["materials"]["hmx"])
    for key in ("specific_heat", "conductivity", "expansion"):
        m.pop(key)
    k0, g, rho, s = m["bulk"], m["shear"], m["density"], m["eos_s"]
    y = math.sqrt(3.0) * m["A"]

    def axial(eta):
        return k0 * eta / (1.0 - s * eta) ** 2 + 2.0 * y / 3.0

    eta_y = y / (2.0 * g)
    sig_hel = axial(eta_y)
    u_hel = math.sqrt(sig_hel * eta_y / rho)
    # The plastic jump from the elastic limit to the piston's speed, by bisection in eta
    lo, hi = eta_y, 0.3
    for _ in range(200):
        mid = 0.5 * (lo + hi)
        du = math.sqrt((axial(mid) - sig_hel) * (mid - eta_y) / rho)
        lo, hi = (mid, hi) if u_hel + du < UP else (lo, mid)
    eta2 = 0.5 * (lo + hi)
    waves = {"c_l": math.sqrt((k0 + 4.0 * g / 3.0) / rho),
             "u_hel": u_hel, "sig_hel": sig_hel, "us_hel": u_hel / eta_y,
             "us_plastic": math.sqrt((axial(eta2) - sig_hel) / (rho * (eta2 - eta_y))),
             "sig2": axial(eta2)}
    return m, waves


def _passage(a, level):
    """Per node (initial height, time its downward speed first reaches ``level``), by linear
    interpolation between frames."""
    t, y0, vy = a["frames/time"], a["frames/x"][0, :, 1], -a["frames/v"][:, :, 1]
    pts = []
    for i in range(y0.shape[0]):
        k = np.nonzero(vy[:, i] >= level)[0]
        if k.size and k[0] > 0:
            k = k[0]
            frac = (level - vy[k - 1, i]) / (vy[k, i] - vy[k - 1, i])
            pts.append((y0[i], t[k - 1] + frac * (t[k] - t[k - 1])))
    return np.array(pts)


def _speed(pts):
    """Lagrangian speed of a front from its passage over the middle of the column."""
    mid = (pts[:, 0] < 0.8 * HEIGHT) & (pts[:, 0] > 0.3 * HEIGHT)
    return -np.polyfit(pts[mid, 1], pts[mid, 0], 1)[0]


def _position(a, level):
    """Initial height where the last frame's downward speed crosses ``level`` (the lowest)."""
    y0, v = a["frames/x"][0, :, 1], -a["frames/v"][-1, :, 1]
    order = np.argsort(y0)
    return y0[order][np.nonzero(v[order] >= level)[0][0]]


@pytest.fixture(scope="module")
def run(tmp_path_factory):
    """The column of the default scene's crystal, 2 x 2 rule, struck at UP."""
    m, waves = _crystal()
    doc = crystal_column(UP, height=HEIGHT, ny=300, rule="2x2")
    doc["materials"] = {"hmx": m}
    doc["output"]["interval"] = doc["time"]["end"] / 100
    cwd = tmp_path_factory.mktemp("precursor")
    write_scene(Path(cwd) / "c.toml", doc)
    p = pdfem(["run", "c.toml", "--quiet"], cwd)
    assert p.returncode == 0, p.stderr
    return datasets(Path(cwd) / "c.h5"), waves


def test_the_precursor_runs_on_its_rayleigh_line_with_the_elastic_limit(run):
    a, w = run
    # The precursor: a weak shock to the elastic limit, faster than the longitudinal speed at
    # rest by the equation of state's stiffening (3283 against 3126 m/s)
    us = _speed(_passage(a, 0.5 * w["u_hel"]))
    assert us == pytest.approx(w["us_hel"], rel=0.01)
    assert us > 1.03 * w["c_l"]
    # Between the two waves: the elastic limit's particle velocity and axial stress
    top = _position(a, 0.5 * (w["u_hel"] + UP))
    bottom = _position(a, 0.5 * w["u_hel"])
    lo, hi = bottom + (top - bottom) / 3.0, top - (top - bottom) / 3.0
    y0 = a["frames/x"][0, :, 1]
    nodes = (y0 > lo) & (y0 < hi)
    assert nodes.sum() >= 3
    assert np.median(-a["frames/v"][-1, nodes, 1]) == pytest.approx(w["u_hel"], rel=0.02)
    # Elements in the same band (rows of the column, bottom up: one element per row)
    rows = (np.arange(a["frames/stress"].shape[1]) + 0.5) * HEIGHT / a["frames/stress"].shape[1]
    band = (rows > lo) & (rows < hi)
    syy = a["frames/stress"][-1, band, :, 1].mean(axis=1)
    assert -np.median(syy) == pytest.approx(w["sig_hel"], rel=0.02)


def test_the_plastic_wave_follows_at_its_own_speed_to_the_piston_state(run):
    a, w = run
    us = _speed(_passage(a, 0.5 * (w["u_hel"] + UP)))
    assert us == pytest.approx(w["us_plastic"], rel=0.01)
    assert us < 0.95 * w["us_hel"]
    # Behind it the piston's stress (the elements next to the driven top)
    syy = a["frames/stress"][-1, -30:, :, 1].mean(axis=1)
    assert -np.median(syy) == pytest.approx(w["sig2"], rel=0.01)
