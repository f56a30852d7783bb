"""Bulk viscosity kernel against closed forms, and its energy through the solver."""

import numpy as np
import pytest
from mpi4py import MPI

from pdfem.energy import balance, global_terms
from pdfem.kernels.params import BULK, NPAR, RHO, SHEAR
from pdfem.kernels.viscosity import bulk_viscosity_dt, bulk_viscosity_forces
from pdfem.scene import parse_scene
from pdfem.solver import Simulation
from tests.scenes import stretched_block

SQUARE = np.array([[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]])


def _material():
    p = np.zeros((1, NPAR))
    p[0, RHO], p[0, BULK], p[0, SHEAR] = 2000.0, 3.0e9, 1.5e9
    return p


def _one(scale_old, dt=1e-6, cq=1.5, cl=0.06, q_old=0.0):
    """The unit square now, (scale_old x) the square one step ago; (q, f, ewq, dt_visc)."""
    x = SQUARE.copy()
    du = x - scale_old * SQUARE
    conn = np.array([[0, 1, 2, 3]], np.int64)
    qv, ewq, f = np.array([q_old]), np.zeros(1), np.zeros((4, 2))
    args = (x, du, conn, np.zeros(1, np.int64), _material(), np.zeros((1, 1, 4)), 0, 1, dt,
            cq, cl)
    bulk_viscosity_forces(*args, qv, ewq, f)
    return qv[0], f, ewq[0], bulk_viscosity_dt(*args, np.zeros((0, 2)))


def test_compression_closed_form():
    dt, cq, cl = 1e-6, 1.5, 0.06
    q, f, ewq, dtv = _one(1.01, dt, cq, cl)
    a, a_old = 1.0, 1.01 ** 2
    rate = (a - a_old) / (0.5 * (a + a_old) * dt)
    c = np.sqrt((3.0e9 + 4 * 1.5e9 / 3) / 2000.0)
    assert q == pytest.approx(2000.0 * (cq * rate ** 2 - cl * c * rate), rel=1e-13)
    # Forces: q times the area gradient, outward (they sum to zero)
    grad = 0.5 * np.array([[-1.0, -1.0], [1.0, -1.0], [1.0, 1.0], [-1.0, 1.0]])
    assert f == pytest.approx(q * grad, rel=1e-14)
    # Work: trapezoid of the old (0) and new pressures over the area change
    assert ewq == pytest.approx(0.5 * q * (a_old - a), rel=1e-13)
    # L = sqrt(A) = 1, L_e = A / diagonal = 1/sqrt(2): Q = (L / L_e) (c_lin c + c_quad L |rate|)
    big_q = np.sqrt(2) * (cl * c - cq * rate)
    assert dtv == pytest.approx((1 / np.sqrt(2)) / (big_q + np.sqrt(big_q ** 2 + c ** 2)),
                                rel=1e-13)


@pytest.mark.parametrize("aspect", [1.0, 10.0, 100.0, 1000.0])
@pytest.mark.parametrize("speed", [1.0, 100.0, 3000.0])
def test_the_bound_holds_the_viscosity_of_a_sliver(aspect, speed):
    """A rectangle h thin and aspect x h long, its long top edge moving down at ``speed``: the
    viscous pressure is a damper on the top nodes, C = dF/dw, whose explicit (lagged) limit
    is dt <= 2 m / C with the lumped mass m = rho A / 4. The bound stays below that limit at
    every aspect (without the factor L / L_e it exceeds it up to 3-fold at aspect 10, 10-fold
    at 100 and 30-fold at 1000)."""
    h = 1.0e-6
    w = aspect * h
    x = np.array([[0.0, 0.0], [w, 0.0], [w, h], [0.0, h]])
    dt = 1.0e-13
    du = np.zeros((4, 2))
    du[2:, 1] = -speed * dt
    conn = np.array([[0, 1, 2, 3]], np.int64)
    mat = _material()
    args = (x, du, conn, np.zeros(1, np.int64), mat, np.zeros((1, 1, 4)), 0, 1, dt, 1.5, 0.06)
    dtv = bulk_viscosity_dt(*args, np.zeros((0, 2)))

    # The damper, from the kernel's own forces: the top nodes' y force against the speed
    def force(v):
        d = np.zeros((4, 2))
        d[2:, 1] = -v * dt
        f = np.zeros((4, 2))
        bulk_viscosity_forces(x, d, conn, np.zeros(1, np.int64), mat, np.zeros((1, 1, 4)), 0,
                              1, dt, 1.5, 0.06, np.zeros(1), np.zeros(1), f)
        return f[2, 1]
    dv = 1.0e-4 * speed
    damper = (force(speed + dv) - force(speed - dv)) / (2 * dv)
    m = mat[0, RHO] * w * h / 4
    assert 0.0 < dtv <= 2 * m / damper


def test_expansion_has_no_viscosity():
    q, f, ewq, dtv = _one(0.99, q_old=5.0)
    assert q == 0.0 and not f.any() and dtv == np.inf
    # The old pressure still works over half of the step (it pushed the expansion)
    assert ewq == pytest.approx(0.5 * 5.0 * (0.99 ** 2 - 1.0), rel=1e-13)


def _compress(tmp_path, extra):
    """A bar hit at 20 m/s on its right end, with the tables of ``extra`` (a dict); (energy
    balance error, viscous term or None when the run has none)."""
    sim = Simulation(parse_scene(stretched_block(end=4e-6, v=-20.0, extra=extra),
                                 str(tmp_path)), MPI.COMM_SELF)
    ref = global_terms(sim.state, sim.ctx)
    while sim.t < sim.t_end:
        sim.step()
    terms = global_terms(sim.state, sim.ctx)
    return balance(terms, ref)[1], terms.get("viscous")


def test_bar_impact_energy_closes_with_viscosity(tmp_path):
    err0, visc0 = _compress(tmp_path, None)
    err1, visc1 = _compress(tmp_path, {"bulk_viscosity": {}})
    # Without [bulk_viscosity] the run has no viscous term
    assert visc0 is None and visc1 > 0.0
    assert err1 < 1e-3 and err0 < 1e-3
