"""What a step does with its evaluated contacts (pdfem.kernels.contact): add their nodal forces
in key order, and the contacts' limits on the time step (contact_law.contact_dt over the active
contacts, over every boundary edge a contact may begin on, and the fastest node's approach).

Layout of the contact arrays (active, nodes, weights, fnod, res) as in pdfem.kernels.contact.
"""

import numpy as np
from numba import njit

from pdfem.kernels.contact import (
    C_ACTIVE,
    R_DAMP,
    R_DELTA,
    R_DISS,
    R_ENERGY,
    R_KSL,
    R_LEN,
    R_MEFF,
    R_STIFF,
    R_WIDTH,
)
from pdfem.kernels.contact_law import contact_dt


@njit(cache=True)
def accumulate_sorted(order, active, nodes, fnod, n_owned, f):
    """Add the nodal forces of the active contacts order[0], order[1], ... to f (nn, 2).

    Node nodes[p, k] of contact p gets fnod[p, k]. Only owned nodes 0 <= node < n_owned receive
    force (ghosts and walls are skipped), in exactly the given order: pass contacts sorted by
    global key for rank-independent bits.
    """
    for i in range(order.shape[0]):
        p = order[i]
        if active[p] != C_ACTIVE:
            continue
        for k in range(nodes.shape[1]):
            nd = nodes[p, k]
            if nd < 0 or nd >= n_owned:
                continue
            f[nd, 0] += fnod[p, k, 0]
            f[nd, 1] += fnod[p, k, 1]


@njit(cache=True)
def first_guarded(active, res, delta_max):
    """First row that trips a guard: a guard code (active < 0), or an active contact whose mean
    overlap res[:, R_DELTA] exceeds delta_max; -1 when none."""
    for r in range(active.shape[0]):
        if active[r] < 0 or (active[r] == C_ACTIVE and res[r, R_DELTA] > delta_max):
            return r
    return -1


@njit(cache=True)
def contact_bookkeeping(active, keys, us_out, res, elems, elem_body, isglobal, nb_own, all_mine,
                        energy, fric, damp):
    """History table and per-body sums of the active contacts (rows in key order).

    Returns (hkey, hval): the keys and new shear histories of the active rows, in their order.
    The stored energy, frictional and damping dissipation of each active row (res columns
    R_ENERGY, R_DISS, R_DAMP) are added to energy, fric, damp (nbody,) at the body of its side
    A (elems[:, 0]'s body) when that body is owned (< nb_own) and, unless all_mine, a grain
    (isglobal 0): a block's contacts are counted by one rank. Each body's sum runs in row order
    from its value on entry (np.bincount's order).
    """
    n = 0
    for r in range(active.shape[0]):
        if active[r] == C_ACTIVE:
            n += 1
    hkey = np.empty((n, 4), np.int64)
    hval = np.empty(n)
    i = 0
    for r in range(active.shape[0]):
        if active[r] != C_ACTIVE:
            continue
        for c in range(4):
            hkey[i, c] = keys[r, c]
        hval[i] = us_out[r]
        i += 1
        b = elem_body[elems[r, 0]]
        if b >= nb_own or not (all_mine or isglobal[b] == 0):
            continue
        energy[b] += res[r, R_ENERGY]
        fric[b] += res[r, R_DISS]
        damp[b] += res[r, R_DAMP]
    return hkey, hval


@njit(cache=True)
def _dt_of_least_ratio(ratio, zeta):
    """contact_law.contact_dt of the spring with the least mass-to-stiffness ratio against a
    rigid partner (inf when there is none). contact_dt(m, rigid, k) rounds sqrt(m / k) times
    a positive factor, non-decreasing in m / k, so the least step over many springs is that of
    the least ratio, bit for bit: one square root instead of two per spring."""
    if ratio == np.inf:
        return np.inf
    return contact_dt(ratio, np.inf, 1.0, zeta)


@njit(cache=True)
def contact_dt_min(active, res, zeta):
    """Smallest stable step over the active contacts (contact_law.contact_dt).

    A contact's normal spring is k_t w^2 / L (k_t = res[:, R_STIFF], w the overlap's width, L
    the pair's length): take w = max(width, L), the widest the overlap of the pair can grow to
    within a few steps, and the larger of that and the shear spring ks L, between the sides'
    effective mass res[:, R_MEFF] and a rigid partner. Returns inf when no contact is active.
    """
    ratio = np.inf
    for p in range(active.shape[0]):
        if active[p] != C_ACTIVE:
            continue
        span = max(res[p, R_WIDTH], res[p, R_LEN])
        k = max(res[p, R_STIFF] * span * span / res[p, R_LEN], res[p, R_KSL])
        if k > 0.0:
            ratio = min(ratio, res[p, R_MEFF] / k)
    return _dt_of_least_ratio(ratio, zeta)


@njit(cache=True)
def max_speed(v, n0, n1):
    """Largest node speed |v| over nodes n0 <= i < n1 (0 when there are none)."""
    s = 0.0
    for i in range(n0, n1):
        s = max(s, v[i, 0] * v[i, 0] + v[i, 1] * v[i, 1])
    return np.sqrt(s)


@njit(cache=True)
def entry_dt_min(x, conn, ebnd, elen, m, e0, e1, kn0, zeta):
    """Stable step of a contact about to begin, over the boundary edges of elements [e0, e1).

    A contact can start on any boundary edge during a step; its normal spring is then
    kn0 w^2 / L (contact.py) with the width w up to the edge's length now, le, and L <= elen[e]:
    kn0 le^2 / elen[e], with le at least elen[e]. Each edge gives contact_dt(m, inf, that) with m
    the smaller lumped mass of its two nodes (the stiffest case: the other side rigid). Taking
    this every step means no contact is ever entered with a step its initial stiffness cannot
    carry. Returns inf when there is no boundary edge.
    """
    ratio = np.inf
    for e in range(e0, e1):
        for k in range(4):
            if ebnd[e, k] == 0 or not elen[e] > 0.0:
                continue
            a = conn[e, k]
            b = conn[e, (k + 1) % 4]
            dx = x[b, 0] - x[a, 0]
            dy = x[b, 1] - x[a, 1]
            le2 = max(dx * dx + dy * dy, elen[e] * elen[e])
            stiff = kn0 * le2 / elen[e]
            if stiff > 0.0:
                ratio = min(ratio, min(m[a], m[b]) / stiff)
    return _dt_of_least_ratio(ratio, zeta)
