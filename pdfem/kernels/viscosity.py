"""Artificial bulk viscosity of the elements (von Neumann-Richtmyer, with a linear term).

Sign convention: tension positive; the viscous pressure q >= 0 acts only while an element's
area shrinks. Per element, over the step with displacement increments du and time step dt:

    A, A_old = area at x and at x - du;  rate = (A - A_old) / (A_mid dt),  A_mid = (A + A_old)/2
    q = rho (c_quad L^2 rate^2 - c_lin c L rate)   if rate < 0, else 0,    L = sqrt(A),
    c = sqrt((K + 4G/3) / rho)  (table density and moduli).

The pressure q enters the residual as the forces of the stress -q I at the current
configuration, f_I += q A b_I (outward), A b_I = ((y_{I+1} - y_{I-1}), (x_{I-1} - x_{I+1})) / 2.
Its work is the trapezoid of the old and new pressures over the area change, the pairing that
matches central differences (a force at t_n works over [t_{n-1/2}, t_{n+1/2}]):

    ewq += (q_old + q) (A_old - A) / 2,

which the energy balance counts as dissipated. The stable step is reduced with the usual
bound for a viscosity of the element's own length, dt_e = L_e / (Q + sqrt(Q^2 + c^2)), with
L_e = A / longest diagonal (the elastic step's length, the element's thinnest extent) and

    Q = (L / L_e) (c_lin c + c_quad L |rate|)   while compressing.

The factor L / L_e makes the bound that of the viscosity as defined, on L = sqrt(A): written
over L_e, q = rho L_e ((L/L_e) c_lin c |rate| + (L/L_e) c_quad L rate^2), i.e. coefficients
L/L_e times larger. It is sqrt(2) for a square and grows as sqrt(aspect) for a sliver, where
a bound without it would allow steps several times too long (a viscous instability).
Before the first step there is no area change yet; the bound of the first step takes the
rate of the initial velocities, (dA/dt) / A with dA/dt the derivative of the area along them
(zero, exactly, for a body that moves rigidly in translation), so that a velocity condition
that starts nodes moving against material at rest (an impulsive start) gets a first step as
short as the ones that follow it.
"""

import numpy as np
from numba import njit

from pdfem.kernels.eos import wave_speed
from pdfem.kernels.params import RHO
from pdfem.kernels.stable import element_length


@njit(cache=True)
def _areas(x, du, conn, e):
    """Area of element e at x and at x - du (half the cross product of the diagonals)."""
    n1 = conn[e, 0]
    n2 = conn[e, 1]
    n3 = conn[e, 2]
    n4 = conn[e, 3]
    a = 0.5 * ((x[n3, 0] - x[n1, 0]) * (x[n4, 1] - x[n2, 1])
               - (x[n4, 0] - x[n2, 0]) * (x[n3, 1] - x[n1, 1]))
    d1x = (x[n3, 0] - du[n3, 0]) - (x[n1, 0] - du[n1, 0])
    d1y = (x[n3, 1] - du[n3, 1]) - (x[n1, 1] - du[n1, 1])
    d2x = (x[n4, 0] - du[n4, 0]) - (x[n2, 0] - du[n2, 0])
    d2y = (x[n4, 1] - du[n4, 1]) - (x[n2, 1] - du[n2, 1])
    return a, 0.5 * (d1x * d2y - d2x * d1y)


@njit(cache=True)
def _rate(a, a_old, dt):
    """Areal strain rate of the step (0 for a degenerate element or dt = 0)."""
    am = 0.5 * (a + a_old)
    if dt <= 0.0 or am <= 0.0 or a <= 0.0:
        return 0.0
    return (a - a_old) / (am * dt)


@njit(cache=True)
def bulk_viscosity_forces(x, du, conn, emat, mat_params, sig, e0, e1, dt, c_quad, c_lin, qv,
                          ewq, f):
    """Viscous pressures of elements [e0, e1) (stored in qv), their forces added to f and
    their work added to ewq (module docstring)."""
    for e in range(e0, e1):
        a, a_old = _areas(x, du, conn, e)
        rate = _rate(a, a_old, dt)
        q = 0.0
        if rate < 0.0:
            p = mat_params[emat[e]]
            rho = p[RHO]
            c = wave_speed(p, sig, e)
            le = np.sqrt(a)
            q = rho * (c_quad * le * le * rate * rate - c_lin * c * le * rate)
        ewq[e] += 0.5 * (qv[e] + q) * (a_old - a)
        qv[e] = q
        if q == 0.0:
            continue
        # Forces of the pressure on the four nodes (outward)
        for i in range(4):
            n = conn[e, i]
            nxt = conn[e, (i + 1) % 4]
            prv = conn[e, (i + 3) % 4]
            f[n, 0] += 0.5 * q * (x[nxt, 1] - x[prv, 1])
            f[n, 1] += 0.5 * q * (x[prv, 0] - x[nxt, 0])


@njit(cache=True)
def _velocity_rate(x, v, conn, e):
    """(dA/dt) / A of element e along the nodal velocities v (0 for a degenerate element)."""
    n1 = conn[e, 0]
    n2 = conn[e, 1]
    n3 = conn[e, 2]
    n4 = conn[e, 3]
    d1x, d1y = x[n3, 0] - x[n1, 0], x[n3, 1] - x[n1, 1]
    d2x, d2y = x[n4, 0] - x[n2, 0], x[n4, 1] - x[n2, 1]
    a = 0.5 * (d1x * d2y - d2x * d1y)
    if a <= 0.0:
        return 0.0
    # Diagonals' rates: zero for a uniform velocity
    w1x, w1y = v[n3, 0] - v[n1, 0], v[n3, 1] - v[n1, 1]
    w2x, w2y = v[n4, 0] - v[n2, 0], v[n4, 1] - v[n2, 1]
    return 0.5 * (w1x * d2y + d1x * w2y - w2x * d1y - d2x * w1y) / a


@njit(cache=True)
def bulk_viscosity_dt(x, du, conn, emat, mat_params, sig, e0, e1, dt, c_quad, c_lin, v):
    """Smallest stable step of elements [e0, e1) with their viscosity (module docstring);
    +inf when none is compressing. v (nn, 2): the velocities whose rate bounds the first
    step (shape (0, 2): the step that has been taken, du over dt)."""
    out = np.inf
    first = v.shape[0] > 0
    for e in range(e0, e1):
        if first:
            rate = _velocity_rate(x, v, conn, e)
        else:
            a, a_old = _areas(x, du, conn, e)
            rate = _rate(a, a_old, dt)
        if rate >= 0.0:
            continue
        c = wave_speed(mat_params[emat[e]], sig, e)
        a_now, le = element_length(x, conn, e)
        if first:
            a = a_now
        if le <= 0.0:
            return 0.0
        lv = np.sqrt(a)
        big_q = (lv / le) * (c_lin * c - c_quad * lv * rate)
        out = min(out, le / (big_q + np.sqrt(big_q * big_q + c * c)))
    return out
