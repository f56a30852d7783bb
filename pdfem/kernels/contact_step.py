"""What a step does with its evaluated contacts (pdfem.kernels.contact): add their nodal forces
in key order, and the contacts' limits on the time step (contact_law.contact_dt over the active
contacts, over every boundary edge a contact may begin on, and the fastest node's approach).

Layout of the contact arrays (active, nodes, weights, fa, res) as in pdfem.kernels.contact.
"""

import numpy as np
from numba import njit

from pdfem.kernels.contact import C_ACTIVE, R_STIFF, R_WIDTH
from pdfem.kernels.contact_law import contact_dt


@njit(cache=True)
def accumulate_sorted(order, active, nodes, weights, fa, n_owned, f):
    """Add the nodal forces of the active contacts order[0], order[1], ... to f (nn, 2).

    Node k of contact p gets +weights[p, k] fa[p] (k = 0, 1: side A) or -weights[p, k] fa[p]
    (k = 2, 3: side B). Only owned nodes 0 <= node < n_owned receive force (ghosts and walls are
    skipped), in exactly the given order: pass contacts sorted by global key for rank-independent
    bits.
    """
    for i in range(order.shape[0]):
        p = order[i]
        if active[p] != C_ACTIVE:
            continue
        for k in range(4):
            nd = nodes[p, k]
            if nd < 0 or nd >= n_owned:
                continue
            w = weights[p, k] if k < 2 else -weights[p, k]
            f[nd, 0] += w * fa[p, 0]
            f[nd, 1] += w * fa[p, 1]


@njit(cache=True)
def contact_dt_min(active, nodes, res, m, x, zeta):
    """Smallest stable step over the active contacts (contact_law.contact_dt).

    The stiffness is the current tangent stiffness res[:, R_STIFF] scaled from the overlap
    width up to the longer contact edge: a contact that has just begun is narrow, and its
    stiffness grows with its width within the next steps. Each side's mass is the smaller lumped
    mass m of its edge's nodes, a wall side is rigid. Returns inf when no contact is active.
    """
    dt = np.inf
    for p in range(active.shape[0]):
        if active[p] != C_ACTIVE:
            continue
        # Longest edge of the two sides (the widest the overlap of this pair can become)
        span = res[p, R_WIDTH]
        for j in (0, 2):
            if nodes[p, j] < 0:
                continue
            dx = x[nodes[p, j + 1], 0] - x[nodes[p, j], 0]
            dy = x[nodes[p, j + 1], 1] - x[nodes[p, j], 1]
            span = max(span, np.sqrt(dx * dx + dy * dy))
        k = res[p, R_STIFF]
        if res[p, R_WIDTH] > 0.0:
            k *= span / res[p, R_WIDTH]
        ma = min(m[nodes[p, 0]], m[nodes[p, 1]])
        mb = np.inf if nodes[p, 2] < 0 else min(m[nodes[p, 2]], m[nodes[p, 3]])
        dt = min(dt, contact_dt(ma, mb, k, zeta))
    return dt


@njit(cache=True)
def max_speed(v, n0, n1):
    """Largest node speed |v| over nodes n0 <= i < n1 (0 when there are none)."""
    s = 0.0
    for i in range(n0, n1):
        s = max(s, v[i, 0] * v[i, 0] + v[i, 1] * v[i, 1])
    return np.sqrt(s)


@njit(cache=True)
def entry_dt_min(x, conn, ebnd, m, e0, e1, kn0, zeta):
    """Stable step of a contact about to begin, over the boundary edges of elements [e0, e1).

    A contact can start on any boundary edge during a step; its stiffness is then at least
    kn0 times the width it can reach, the edge length L. Each edge gives contact_dt(m, inf,
    kn0 L) with m the smaller lumped mass of its two nodes (the stiffest case: the other
    side rigid). Taking this every step means no contact is ever entered with a step its
    initial stiffness cannot carry. Returns inf when there is no boundary edge.
    """
    dt = np.inf
    for e in range(e0, e1):
        for k in range(4):
            if ebnd[e, k] == 0:
                continue
            a = conn[e, k]
            b = conn[e, (k + 1) % 4]
            dx = x[b, 0] - x[a, 0]
            dy = x[b, 1] - x[a, 1]
            le = np.sqrt(dx * dx + dy * dy)
            dt = min(dt, contact_dt(min(m[a], m[b]), np.inf, kn0 * le, zeta))
    return dt
