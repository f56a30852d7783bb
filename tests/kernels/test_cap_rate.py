"""Rate-dependent cap (Duvaut-Lions overstress): closed forms of the relaxation, the
rate-independent limit, and the material-point driver's strain rate.

Units are ksi and seconds (the kernel is unit-agnostic). Tension positive.
"""

import math

import numpy as np
import pytest

from pdfem.errors import InputError
from pdfem.kernels import params as P
from pdfem.kernels.cap import CAP_NST, cap_initial_state, cap_update, cap_yield_value
from pdfem.material_point import run_path
from tests.kernels.test_cap import mccormick


def flat(tau):
    """A cap with a flat envelope (B = 0: sqrt(J2) <= Y = A - C at every I1), so that pure
    shear at I1 = 0 flows without volume change or hardening."""
    p = np.zeros(P.NPAR)
    p[P.MODEL] = P.CAP
    p[P.RHO] = 1.0
    p[P.BULK], p[P.SHEAR] = 66.67, 40.0
    p[P.CAP_A], p[P.CAP_B], p[P.CAP_C], p[P.CAP_D] = 0.25, 0.0, 0.05, 0.67
    p[P.CAP_R], p[P.CAP_W], p[P.CAP_KAPPA0] = 2.5, 0.066, -0.5
    p[P.CAP_TAU] = tau
    return p


def at_yield(p):
    """Pure shear stress exactly on the envelope (sigma_xy = Y) and the initial state."""
    st = np.zeros(CAP_NST)
    cap_initial_state(p, st)
    return np.array([0.0, 0.0, p[P.CAP_A] - p[P.CAP_C], 0.0]), st


def test_overstress_under_constant_shear_rate_is_backward_euler_of_its_ode():
    """Sheared at a constant rate from the surface, the overstress o = sigma_xy - Y obeys
    do/dt = 2 G gdot - o / tau. The update is its backward Euler step, o_n = 2 G gdot tau
    (1 - (1 + dt/tau)^-n) exactly, and tends to the ODE's 2 G gdot tau (1 - exp(-t/tau)) as
    dt / tau -> 0. Its plastic work is sigma_xy (trial - sigma_xy) / G per step, >= 0."""
    tau, rate = 1e-6, 1e3  # s, 1/s (tensor shear strain rate)
    p = flat(tau)
    y, g2 = p[P.CAP_A] - p[P.CAP_C], 2.0 * p[P.SHEAR]
    for n_per_tau in (20, 2000):
        dt = tau / n_per_tau
        sig, st = at_yield(p)
        d = np.array([0.0, 0.0, rate * dt, 0.0])
        epxy = 0.0
        for n in range(1, 3 * n_per_tau + 1):
            trial = sig[2] + g2 * d[2]
            status, dwp = cap_update(p, sig, d, st, dt)
            assert status == 0
            o = sig[2] - y
            assert o == pytest.approx(g2 * rate * tau * (1.0 - (1.0 + dt / tau) ** -n),
                                      rel=1e-10)
            assert dwp == pytest.approx(sig[2] * (trial - sig[2]) / p[P.SHEAR], rel=1e-10)
            assert dwp > 0.0
            # No volume change, no hardening, the stress outside the surface by o
            assert sig[0] == sig[1] == sig[3] == 0.0 and st[1] == 0.0
            epxy += (trial - sig[2]) / g2
            assert st[4] == pytest.approx(epxy, rel=1e-10)
        ode = g2 * rate * tau * (1.0 - math.exp(-3.0))
        assert o == pytest.approx(ode, rel=2.0 / n_per_tau)
    assert cap_yield_value(p, sig, st) > 0.0


def test_overstress_relaxes_geometrically_at_fixed_strain():
    """Held at fixed strain, an overstressed point relaxes to the surface: o_n = o_0 (1 +
    dt/tau)^-n, exp(-t/tau) as dt -> 0; the plastic strain grows by what the stress loses."""
    tau, dt = 1e-6, 1e-8
    p = flat(tau)
    y = p[P.CAP_A] - p[P.CAP_C]
    sig, st = at_yield(p)
    o0 = 0.3 * y
    sig[2] += o0
    zero = np.zeros(4)
    for n in range(1, 301):
        status, dwp = cap_update(p, sig, zero, st, dt)
        assert status == 0 and dwp > 0.0
        assert sig[2] - y == pytest.approx(o0 * (1.0 + dt / tau) ** -n, rel=1e-10)
    # The shear plastic strain took up the lost stress: G 2 eps^p_xy = o0 - o
    assert 2.0 * p[P.SHEAR] * st[4] == pytest.approx(o0 - (sig[2] - y), rel=1e-10)
    assert sig[2] - y == pytest.approx(o0 * math.exp(-3.0), rel=0.02)


def test_a_step_of_no_duration_is_elastic():
    """dt = 0: no time to relax, the trial stands (and no plastic work)."""
    p = flat(1e-6)
    sig, st = at_yield(p)
    st0 = st.copy()
    status, dwp = cap_update(p, sig, np.array([0.0, 0.0, 1e-3, 0.0]), st, 0.0)
    assert status == 0 and dwp == 0.0
    assert sig[2] == p[P.CAP_A] - p[P.CAP_C] + 2.0 * p[P.SHEAR] * 1e-3
    assert np.array_equal(st, st0)


def _random_path(p, dt, seed=3, n=400):
    """Stress, state and plastic work after n random increments (cap, envelope, corners)."""
    rng = np.random.default_rng(seed)
    sig = np.zeros(4)
    st = np.zeros(CAP_NST)
    cap_initial_state(p, st)
    wp = 0.0
    for _ in range(n):
        d = rng.normal(0.0, 1.5e-3, 4) + np.array([-1.2e-3, -0.6e-3, 0.0, -0.3e-3])
        status, dwp = cap_update(p, sig, d, st, dt)
        assert status == 0
        wp += dwp
    return sig, st, wp


def test_zero_relaxation_time_is_the_rate_independent_update_and_the_limit_of_small_ones():
    """relaxation_time = 0 ignores dt (the rate-independent bits); a relaxation time 1e-9 of
    the step gives the same answer to round-off along a path over cap, envelope and
    corners (McCormick sand)."""
    p0 = mccormick()
    ref = _random_path(p0, 0.0)
    same = _random_path(p0, 1e-7)
    for a, b in zip(ref[:2], same[:2], strict=True):
        assert np.array_equal(a, b)
    assert ref[2] == same[2]
    p = p0.copy()
    p[P.CAP_TAU] = 1e-16
    near = _random_path(p, 1e-7)
    scale = np.abs(ref[0]).max()
    assert np.abs(near[0] - ref[0]).max() <= 1e-7 * scale
    assert np.abs(near[1] - ref[1]).max() <= 1e-7 * (np.abs(ref[1]).max())
    assert near[2] == pytest.approx(ref[2], rel=1e-6)
    # A slow point (tau of 100 steps) lags behind: the stress outside the rate-independent one
    p[P.CAP_TAU] = 1e-5
    slow = _random_path(p, 1e-7)
    assert np.abs(slow[0] - ref[0]).max() > 1e-2 * scale


def test_material_driver_needs_a_strain_rate_for_a_rate_dependent_point():
    """run_path refuses a rate-dependent material without --strain-rate; with one, slower
    loading approaches the rate-independent curve (the overstress 2 G gdot tau falls with the
    rate)."""
    p = flat(1e-7)
    path = np.array([[0.0, 0.0, 0.01, 0.0]])
    with pytest.raises(InputError, match="^--strain-rate: needed by a material with "
                                         "relaxation_time > 0"):
        run_path(p, path, 200)
    with pytest.raises(InputError, match="^--strain-rate: must be a rate > 0"):
        run_path(p, path, 200, strain_rate=-1.0)
    y = p[P.CAP_A] - p[P.CAP_C]
    over = [run_path(p, path, 2000, strain_rate=r)["sxy"][-1] - y for r in (1e2, 1e3, 1e4)]
    g2tau = 2.0 * p[P.SHEAR] * p[P.CAP_TAU]
    # Seven relaxation times after yield the overstress is the steady 2 G gdot tau (which the
    # backward Euler step keeps exactly)
    for o, r in zip(over, (1e2, 1e3, 1e4), strict=True):
        assert o == pytest.approx(g2tau * r, rel=1e-3)
