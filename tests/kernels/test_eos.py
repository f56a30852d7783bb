"""The Us-up equation of state against its closed forms: the tangent bulk modulus is
-V dp_H/dV, the pressure a point reaches is p_H of its volume, a closed load-unload cycle
does no work, and materials without it are untouched."""

import numpy as np
import pytest

from pdfem.kernels.eos import eos_row, hugoniot_bulk, hugoniot_pressure, wave_speed
from pdfem.kernels.params import BULK, EOS_S, NPAR, RHO, SHEAR
from pdfem.kernels.viscosity import _velocity_rate

K0, S, RHO0 = 1900.0 * 2770.0**2, 2.29, 1900.0


def _row(s=S):
    p = np.zeros(NPAR)
    p[RHO], p[BULK], p[SHEAR], p[EOS_S] = RHO0, K0, 1.0e9, s
    return p


def _eta(p):
    """eta of pressure p on the Hugoniot, by bisection (independent of the kernel's root)."""
    lo, hi = 0.0, 1.0 / S
    for _ in range(200):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if hugoniot_pressure(K0, S, mid) < p else (lo, mid)
    return 0.5 * (lo + hi)


@pytest.mark.parametrize("p", [1.0e6, 1.0e9, 5.0e9, 2.0e10, 1.0e11])
def test_bulk_is_the_tangent_of_the_hugoniot(p):
    # K = -V dp/dV = (1 - eta) dp/deta, by central differences of p_H at eta(p)
    eta = _eta(p)
    h = 1e-6 * eta
    dp = (hugoniot_pressure(K0, S, eta + h) - hugoniot_pressure(K0, S, eta - h)) / (2 * h)
    assert hugoniot_bulk(K0, S, p) == pytest.approx((1.0 - eta) * dp, rel=1e-8)


def test_linear_in_tension_and_without_slope():
    assert hugoniot_bulk(K0, S, -1.0e9) == K0
    assert hugoniot_bulk(K0, S, 0.0) == K0
    assert hugoniot_bulk(K0, 0.0, 1.0e9) == K0
    # Without an EOS the row itself comes back (no copy: the same bits downstream)
    p = _row(0.0)
    assert eos_row(p, -1e9, -1e9, -1e9, -1e-3, np.empty(NPAR)) is p


@pytest.mark.parametrize("steps", [100, 1000])
def test_compression_ends_on_the_hugoniot(steps):
    # Uniaxial compression to eta = 0.3 in equal increments of ln(V): p -> p_H(0.3), exactly
    # (the secant modulus); the trapezoidal work of the cycle is the quadrature's error
    p, out = _row(), np.empty(NPAR)
    eta_end = 0.3
    dv = np.log(1.0 - eta_end) / steps
    pres = 0.0
    work = 0.0
    for _ in range(steps):
        q = eos_row(p, -pres, -pres, -pres, dv, out)
        new = pres - q[BULK] * dv
        work -= 0.5 * (pres + new) * dv
        pres = new
    exact = hugoniot_pressure(K0, S, eta_end)
    assert pres == pytest.approx(exact, rel=1e-10)
    # And back to the initial volume: p returns to 0 and the cycle does no net work
    pres_up, loading = pres, work
    for _ in range(steps):
        q = eos_row(p, -pres, -pres, -pres, -dv, out)
        new = pres + q[BULK] * dv
        work += 0.5 * (pres + new) * dv
        pres = new
    assert abs(pres) < 1e-10 * pres_up
    assert loading > 0.0 and abs(work) < 20.0 / steps**2 * abs(loading)


def test_wave_speed_follows_the_pressure():
    p = _row()
    sig = np.zeros((1, 4, 4))
    c0 = np.sqrt((K0 + 4.0e9 / 3.0) / RHO0)
    assert wave_speed(p, sig, 0) == pytest.approx(c0, rel=1e-15)
    # The stiffest point sets it
    sig[0, 2, [0, 1, 3]] = -2.0e10
    k = hugoniot_bulk(K0, S, 2.0e10)
    assert wave_speed(p, sig, 0) == pytest.approx(np.sqrt((k + 4.0e9 / 3.0) / RHO0), rel=1e-15)
    assert k > 5 * K0


def test_initial_rate_of_velocities():
    x = np.array([[0.0, 0.0], [2.0, 0.0], [2.0, 1.0], [0.0, 1.0]])
    conn = np.array([[0, 1, 2, 3]], np.int64)
    # Translation: exactly zero; the top pushed down at speed u: -u / height
    v = np.tile([3.7e2, -1.3e3], (4, 1))
    assert _velocity_rate(x, v, conn, 0) == 0.0
    v = np.zeros((4, 2))
    v[2:, 1] = -500.0
    assert _velocity_rate(x, v, conn, 0) == pytest.approx(-500.0, rel=1e-15)


def test_no_division_at_the_limit():
    # Pressures whose eta rounds to 1/s: an infinite modulus, no exception; below, finite
    for p in (1e300, np.inf):
        assert hugoniot_bulk(K0, S, p) == np.inf
    assert K0 < hugoniot_bulk(K0, S, 1e20) < np.inf
