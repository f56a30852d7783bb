"""Contact law: normal force, stiffness and energy, shear stick/slip, stable step."""

import numpy as np
import pytest

from pdfem.kernels import contact_law as L

# ---- contact law ----


def test_normal_law_force_stiffness_energy():
    kn0, dmax, w, rcap = 2e9, 1e-3, 0.01, 1 - 1e-9
    f, k, e = L.normal_force(1e-9, w, kn0, dmax, rcap)
    assert f == pytest.approx(-w * kn0 * 1e-9, rel=1e-5) and e > 0
    assert L.normal_force(0.0, w, kn0, dmax, rcap) == (0.0, w * kn0, 0.0)
    assert L.normal_force(-1e-6, w, kn0, dmax, rcap) == (0.0, 0.0, 0.0)
    # Stiffness diverges as delta -> delta_max
    ks = [L.normal_force(dmax * (1 - g), w, kn0, dmax, rcap)[1] for g in (1e-1, 1e-3, 1e-6)]
    assert ks == pytest.approx([w * kn0 / g**2 for g in (1e-1, 1e-3, 1e-6)], rel=1e-6)
    # Stiffness is the derivative of the force
    for r in [0.01, 0.5, 0.9]:
        h = 1e-7 * dmax
        fp = L.normal_force(r * dmax + h, w, kn0, dmax, rcap)[0]
        fm = L.normal_force(r * dmax - h, w, kn0, dmax, rcap)[0]
        assert -(fp - fm) / (2 * h) == pytest.approx(
            L.normal_force(r * dmax, w, kn0, dmax, rcap)[1], rel=1e-6
        )


@pytest.mark.parametrize("rcap", [0.5, 0.95, 1 - 1e-9])
def test_normal_energy_is_integral_of_force(rcap):
    kn0, dmax, w = 2e9, 1e-3, 0.01
    xg, wg = np.polynomial.legendre.leggauss(40)
    for r in [1e-6, 0.03, 0.3, 0.7, 0.9, 1.2 * rcap]:
        d = r * dmax
        if rcap > 0.9 and r > 0.99:
            continue
        # Piecewise Gauss quadrature (split at the cap) of -F
        edges = sorted({0.0, min(d, rcap * dmax), d})
        q = 0.0
        for lo, hi in zip(edges[:-1], edges[1:], strict=True):
            s = 0.5 * (hi - lo) * xg + 0.5 * (hi + lo)
            q -= (
                0.5
                * (hi - lo)
                * sum(
                    wi * L.normal_force(si, w, kn0, dmax, rcap)[0]
                    for si, wi in zip(s, wg, strict=True)
                )
            )
        assert L.normal_force(d, w, kn0, dmax, rcap)[2] == pytest.approx(q, rel=1e-12)


def test_normal_law_linear_beyond_cap():
    kn0, dmax, w, rcap = 1e9, 1e-3, 1.0, 0.9
    fc, kc, _ = L.normal_force(rcap * dmax, w, kn0, dmax, rcap)
    f2, k2, _ = L.normal_force(2 * dmax, w, kn0, dmax, rcap)
    assert kc == k2 == pytest.approx(kn0 / 0.01)
    assert f2 == pytest.approx(fc - kc * (2 - rcap) * dmax, rel=1e-14)


def test_shear_stick_and_slip():
    w, ks, mu, fn = 0.02, 1e9, 0.4, -1e4
    lim = mu * abs(fn)
    # Stick: elastic, no dissipation
    us, fs, dis = L.shear_update(0.0, 0.5 * lim / (ks * w), w, ks, mu, fn)
    assert fs == pytest.approx(0.5 * lim) and dis == 0.0 and us == pytest.approx(fs / (ks * w))
    # Slip: force at the limit, history on the limit, dissipation = mu |Fn| slip
    slip = 3e-7
    us2, fs2, dis2 = L.shear_update(us, 0.5 * lim / (ks * w) + slip, w, ks, mu, fn)
    assert fs2 == lim and us2 == pytest.approx(lim / (ks * w), rel=1e-15)
    assert dis2 == pytest.approx(mu * abs(fn) * slip, rel=1e-8)
    # Reversal from the limit is elastic again; negative slip is symmetric
    us3, fs3, dis3 = L.shear_update(us2, -1e-8, w, ks, mu, fn)
    assert dis3 == 0.0 and fs3 == pytest.approx(lim - ks * w * 1e-8)
    us4, fs4, dis4 = L.shear_update(0.0, -(lim / (ks * w) + slip), w, ks, mu, fn)
    assert fs4 == -lim and us4 == -us2 and dis4 == pytest.approx(dis2, rel=1e-8)
    # No normal force: no shear force at all
    assert L.shear_update(1e-6, 1e-6, w, ks, mu, 0.0) == (0.0, 0.0, 0.0)


def test_contact_dt():
    assert L.contact_dt(2.0, 2.0, 4.0) == L.DT_FACTOR * 2 * np.sqrt(1.0 / 4.0)
    assert L.contact_dt(2.0, np.inf, 8.0) == L.DT_FACTOR * 2 * np.sqrt(2.0 / 8.0)
    assert L.contact_dt(1.0, 1.0, 0.0) == np.inf
    # The step shrinks with the hardening stiffness
    k1 = L.normal_force(0.1e-3, 0.01, 1e9, 1e-3, 0.99)[1]
    k2 = L.normal_force(0.9e-3, 0.01, 1e9, 1e-3, 0.99)[1]
    assert L.contact_dt(1.0, 1.0, k1) / L.contact_dt(1.0, 1.0, k2) == pytest.approx(9.0)
