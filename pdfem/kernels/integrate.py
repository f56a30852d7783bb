"""Explicit central difference with mass-proportional damping (report eqs. 65-73).

Velocities live at half steps, positions at whole steps. With D = gamma*M and a lumped M,
    v_{n+1/2} = c1 v_{n-1/2} + c2 F_n / m,   c1 = (2 - gamma dt)/(2 + gamma dt),
    c2 = 2 dt/(2 + gamma dt),                 x_{n+1} = x_n + dt_{n+1/2} v_{n+1/2}.
The kinetic energy at step n is the product form K_n = 1/2 m v_{n-1/2} . v_{n+1/2}, which the
undamped scheme conserves exactly together with the strain energy of a linear system.
Every loop runs in node order, so per-body sums are the same on any number of ranks.
"""

import numpy as np
from numba import njit

# Columns of the per-body energy accumulator acc[b, :] (the integrator's; the contacts keep
# their friction and damping losses in a field of their own, pdfem.effects.contact)
ACC_DAMP = 0  # energy dissipated by mass-proportional damping [J/m]
ACC_BC = 1  # work done by boundary-condition reactions [J/m]
ACC_CWORK = 2  # work done by contact forces on the body [J/m]
ACC_DAMP_P = 3  # damping dissipation of the current step's later half interval (pending)
ACC_BC_P = 4  # reaction work of the current step's later half interval (pending)
ACC_CWORK_P = 5  # contact work of the current step's later half interval (pending)
NACC = 6


@njit(cache=True)
def damping_coefficients(gamma, dt):
    """Return (c1, c2) of eqs. 70-71 for damping gamma [1/s] and step dt [s]."""
    c1 = (2.0 - gamma * dt) / (2.0 + gamma * dt)
    c2 = 2.0 * dt / (2.0 + gamma * dt)
    return c1, c2


@njit(cache=True)
def advance_positions(x, v, dt, n1, du):
    """x += dt*v for nodes [0, n1); du receives the increment dt*v (eq. 72)."""
    for i in range(n1):
        for k in range(2):
            d = dt * v[i, k]
            du[i, k] = d
            x[i, k] += d


@njit(cache=True)
def advance_velocities(v, f, m, bcf, bcv, gamma, dt, n1, node_body, acc, kin, first, fc,
                       partner):
    """Eq. 68 with boundary conditions; accumulate damping, reaction and contact work per body.

    bcf[i, k]: 0 free, 1 fixed (velocity 0), 2 prescribed velocity bcv[i, k].
    kin[b] receives the product-form kinetic energy of body b at the current whole step.
    A force F_n acting at step n does work dt F_n v_{n-1/2}/2 in the interval before the
    step and dt F_n v_{n+1/2}/2 in the one after; the second half is kept pending until the
    next step, so that K_n + U_n and the accumulated work balance exactly at every step.
    ``first`` marks the start-up half step, which has no interval before it. fc (nn, 2) is
    the contacts' share of f, whose work is accumulated the same way; shape (0, 2): none.
    partner (np,) ties node i < np to node partner[i] (-1: none; periodic sides: a block's
    left and right columns): both take the velocity of their summed force and mass, added in
    the order of the lower index, and each books its own share of the energies (the tie does
    no work, as the two move together). Shape (0,): no ties.
    """
    contact = fc.shape[0] > 0
    ntied = partner.shape[0]
    c1, c2 = damping_coefficients(gamma, dt)
    # Pending halves of the previous step belong to the interval that just ended
    for b in range(kin.shape[0]):
        kin[b] = 0.0
        acc[b, ACC_DAMP] += acc[b, ACC_DAMP_P]
        acc[b, ACC_BC] += acc[b, ACC_BC_P]
        acc[b, ACC_CWORK] += acc[b, ACC_CWORK_P]
        acc[b, ACC_DAMP_P] = 0.0
        acc[b, ACC_BC_P] = 0.0
        acc[b, ACC_CWORK_P] = 0.0
    before = 0.0 if first else 1.0
    for i in range(n1):
        b = node_body[i]
        mi = m[i]
        p = partner[i] if i < ntied else -1
        for k in range(2):
            vold = v[i, k]
            if p >= 0:
                lo, hi = min(i, p), max(i, p)
                vnew = c1 * vold + c2 * (f[lo, k] + f[hi, k]) / (m[lo] + m[hi])
            else:
                vnew = c1 * vold + c2 * f[i, k] / mi
            # Kinematic constraint: the reaction force is what it takes to impose it
            if bcf[i, k] != 0:
                vbc = 0.0 if bcf[i, k] == 1 else bcv[i, k]
                react = mi * (vbc - vnew) / c2
                vnew = vbc
                acc[b, ACC_BC] += before * 0.5 * dt * react * vold
                acc[b, ACC_BC_P] += 0.5 * dt * react * vnew
            # Damping force -gamma m v_avg does (negative) work on both half intervals
            fd = gamma * mi * 0.5 * (vnew + vold)
            acc[b, ACC_DAMP] += before * 0.5 * dt * fd * vold
            acc[b, ACC_DAMP_P] += 0.5 * dt * fd * vnew
            if contact:
                acc[b, ACC_CWORK] += before * 0.5 * dt * fc[i, k] * vold
                acc[b, ACC_CWORK_P] += 0.5 * dt * fc[i, k] * vnew
            kin[b] += 0.5 * mi * vold * vnew
            v[i, k] = vnew


@njit(cache=True)
def add_gravity(f, m, gx, gy, n1):
    """Body force of gravity on the lumped masses of nodes [0, n1)."""
    for i in range(n1):
        f[i, 0] += m[i] * gx
        f[i, 1] += m[i] * gy


@njit(cache=True)
def body_sums(val, start, count, out):
    """out[b] = sum of val[start[b]: start[b]+count[b]] in index order."""
    for b in range(start.shape[0]):
        s = 0.0
        for i in range(start[b], start[b] + count[b]):
            s += val[i]
        out[b] = s


@njit(cache=True)
def potential_energy(x, m, gx, gy, node_body, n1, out):
    """out[b] = -sum m g.x over the nodes of body b (gravity potential, datum at origin)."""
    for b in range(out.shape[0]):
        out[b] = 0.0
    for i in range(n1):
        out[node_body[i]] -= m[i] * (gx * x[i, 0] + gy * x[i, 1])


@njit(cache=True)
def moves_half_skin(x, xref, v, f, m, bcf, bcv, n0, n1, dt_next, dt_avg, half_skin):
    """True when the next position update may take a node of [n0, n1) farther than
    half_skin from its position at the last rebuild.

    The update is x + dt v' with dt <= dt_next and v' = c1 v + c2 f / m (advance_velocities:
    |c1| <= 1 and 0 <= c2 <= dt_avg for damping gamma >= 0), or the prescribed velocity bcv
    (bcf 2), or 0 (bcf 1). So |x' - xref| <= |x - xref| + dt_next |v'| with each component
    of v' bounded by |v| + dt_avg |f| / m; the bound is compared with a relative margin of
    1e-9 that covers the rounding of the update. dt_avg = 0 bounds a state whose v is
    already the next half step's (after a restart or a rollback).
    """
    for i in range(n0, n1):
        b2 = 0.0
        for k in range(2):
            if bcf[i, k] == 0:
                vk = abs(v[i, k]) + dt_avg * abs(f[i, k]) / m[i]
            elif bcf[i, k] == 2:
                vk = max(abs(bcv[i, k]), abs(v[i, k]))
            else:
                vk = abs(v[i, k])
            b2 += vk * vk
        dx = x[i, 0] - xref[i, 0]
        dy = x[i, 1] - xref[i, 1]
        d = np.sqrt(dx * dx + dy * dy) + dt_next * np.sqrt(b2)
        if d * (1.0 + 1e-9) > half_skin:
            return True
    return False
