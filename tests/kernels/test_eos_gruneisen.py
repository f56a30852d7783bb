"""The Mie-Gruneisen form on the Us-up Hugoniot (pdfem.kernels.eos) through the element's own
point update: the closed-form inverse of its reference curve, the state invariant
p = p_r(eta) + Gamma0 e along any path, energy that returns over a closed cycle, and the
pressure of heat added at constant volume."""

import math

import numpy as np
import pytest

from pdfem.kernels import params as P
from pdfem.kernels.element import _stress_point
from pdfem.kernels.eos import hugoniot_eta, hugoniot_pressure, reference_eta

K0, S, RHO = 1900.0 * 2770.0**2, 2.29, 1900.0


def row(gamma, shear=0.0):
    """An elastic material row with the Us-up equation of state and Gruneisen coefficient."""
    p = np.zeros(P.NPAR)
    p[P.MODEL], p[P.RHO], p[P.BULK], p[P.SHEAR] = P.ELASTIC, RHO, K0, shear
    p[P.EOS_S], p[P.EOS_G] = S, gamma
    return p


def p_ref(eta, gamma):
    """p_H(eta) (1 - Gamma0 eta / 2)."""
    return hugoniot_pressure(K0, S, eta) * (1.0 - 0.5 * gamma * eta)


def step(p, sig, st, dv, dxy=0.0, q=0.0):
    """One uniaxial-strain increment (deps_xx = dv, a shear dxy) of a point, as the 2 x 2
    element updates it; returns the stress work density of the step."""
    buf = [np.empty(4), np.empty(4), np.empty(P.NPAR)]
    status, _, w, _ = _stress_point(p, sig, st, dv, dxy, dxy, 0.0, 1.0, 0.0, 0.0, *buf, 0.0, q)
    assert status == 0
    return w


def pressure(sig):
    return -(sig[0] + sig[1] + sig[3]) / 3.0


@pytest.mark.parametrize("gamma", [0.0, 0.7, 1.5, 4.5])
def test_the_reference_curve_inverts_in_closed_form(gamma):
    for pr in [-2.0e9, -1.0e6, 0.0, 1.0e3, 1.0e8, 3.0e9, 3.0e10, 1.0e12]:
        eta = reference_eta(K0, S, gamma, pr)
        assert eta < 1.0 / S
        assert p_ref(eta, gamma) == pytest.approx(pr, rel=1e-12, abs=1e-3)
        if gamma == 0.0:
            assert eta == pytest.approx(hugoniot_eta(K0, S, pr), rel=1e-14, abs=1e-300)


@pytest.mark.parametrize("shear,q", [(0.0, 0.0), (4.4e9, 0.0), (4.4e9, 2.0e8)])
def test_the_state_stays_on_the_form_along_a_path(shear, q):
    # Compression to eta = 0.3 with shear and (optionally) a viscosity heating the point,
    # then part of the way back: p - Gamma0 e is the reference curve's pressure at the
    # compression of the path's own volume, 1 - exp(sum dv)
    gamma = 1.1
    p, sig, st = row(gamma, shear), np.zeros(4), np.zeros(1)
    dvs = np.concatenate([np.full(600, math.log(0.7) / 600), np.full(200, 0.1 / 200)])
    rng = np.random.default_rng(3)
    total = 0.0
    for i, dv in enumerate(dvs):
        step(p, sig, st, dv, rng.uniform(-1.0, 1.0) * 1.0e-4, q if dv < 0.0 else 0.0)
        total += dv
        eta = 1.0 - math.exp(total)
        if i % 50 == 0 or i == len(dvs) - 1:
            assert pressure(sig) - gamma * st[0] == pytest.approx(p_ref(eta, gamma), rel=1e-6)
    assert st[0] > 0.0


def test_a_closed_cycle_returns_its_energy_and_pressure_to_second_order():
    # Pure volumetric strain without viscosity: along the isentrope of the form and back
    gamma = 1.1
    ends = []
    for n in (100, 1000):
        p, sig, st = row(gamma), np.zeros(4), np.zeros(1)
        for dv in np.concatenate([np.full(n, math.log(0.7) / n), np.full(n, -math.log(0.7) / n)]):
            step(p, sig, st, dv)
        ends.append((abs(st[0]), abs(pressure(sig))))
    e100, e1000 = ends
    assert e1000[0] < 2.0e-2 * e100[0] and e1000[1] < 2.0e-2 * e100[1]
    assert e1000[1] < 1.0e-5 * hugoniot_pressure(K0, S, 0.3)
    assert e1000[0] < 1.0e-5 * 0.5 * hugoniot_pressure(K0, S, 0.3) * 0.3


def test_heat_at_constant_volume_raises_the_pressure_by_gamma_times_it():
    # A shear cycle at fixed volume: its deviatoric work stays as heat in the state's energy
    # and as the pressure Gamma0 e of that heat
    gamma = 1.1
    p, sig, st = row(gamma, 4.4e9), np.zeros(4), np.zeros(1)
    for dxy in np.concatenate([np.full(50, 2.0e-4), np.full(50, -2.0e-4)]):
        step(p, sig, st, 0.0, dxy)
    # The elastic shear cycle returns its work: no heat, no pressure
    assert abs(st[0]) < 1.0e-9 * 4.4e9 * 0.01**2
    # Energy added by a viscosity while the point is compressed one step: the pressure of
    # that step's heat is the form's
    p, sig, st = row(gamma), np.zeros(4), np.zeros(1)
    dv = math.log(0.9)
    step(p, sig, st, dv, q=5.0e8)
    eta = 1.0 - math.exp(dv)
    assert st[0] > 5.0e8 * (-dv) * (1.0 - eta)
    assert pressure(sig) == pytest.approx(p_ref(eta, gamma) + gamma * st[0], rel=1e-3)


def test_the_thermoelastic_heat_follows_the_forms_isentrope_and_returns():
    # [thermoelastic] on an element of the form: its compression heats it by
    # dT = Gamma0 T d(eta), so T = T0 exp(Gamma0 eta) along any path (viscous heat in the
    # point's energy moves p, not eta), and a closed cycle ends at T0
    from pdfem.kernels.heat import NHEAT, coupling_state, element_heat

    gamma, cp, t0, area = 1.1, 1000.0, 300.0, 1.0e-8
    p = row(gamma)
    p[P.CP] = cp
    mat = p[None, :]
    x = np.array([[0.0, 0.0], [1.0e-4, 0.0], [1.0e-4, 1.0e-4], [0.0, 1.0e-4]])
    conn, emat = np.arange(4)[None, :], np.zeros(1, np.int32)
    sig, st = np.zeros((1, 1, 4)), np.zeros((1, 1, 1))
    eth, area_ref, temp = np.zeros((1, 3)), np.array([area]), np.full(4, t0)
    tau_prev, out, eheat, none = np.zeros(1), np.zeros(1), np.zeros((1, NHEAT)), np.empty(0)
    coupling_state(x, conn, emat, mat, sig, st, eth, 0, 1, tau_prev)
    assert tau_prev[0] == 0.0
    ends = []
    for n in (300, 3000):
        sig[:], st[:], temp[:], eheat[:], tau_prev[:] = 0.0, 0.0, t0, 0.0, 0.0
        dvs = np.concatenate([np.full(n, math.log(0.7) / n), np.full(n, -math.log(0.7) / n)])
        total = 0.0
        for i, dv in enumerate(dvs):
            step(p, sig[0, 0], st[0, 0], dv, q=2.0e8 if dv < 0.0 else 0.0)
            element_heat(x, temp, conn, emat, mat, sig, st, eth, area_ref, none, none, none,
                         none, tau_prev, 0.0, 0.0, True, 0, 1, out, eheat)
            temp += out[0] / (RHO * cp * area)
            total += dv
            if i == n - 1:
                assert temp[0] == pytest.approx(t0 * math.exp(gamma * 0.3), rel=2e-3)
        # Heat since t = 0 (the coupling's energy, negative) is the capacity times the rise
        assert eheat[0, 2] == pytest.approx(RHO * cp * area * (temp[0] - t0), rel=1e-12,
                                            abs=1e-12)
        ends.append(abs(temp[0] - t0))
    assert ends[1] < 0.2 * ends[0] and ends[1] < 1.0e-3 * t0
