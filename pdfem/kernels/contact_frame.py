"""Geometry of a contact's overlap polygon (pdfem.kernels.contact): the exact gradient of its area
with respect to the nodes of the two elements, the contact normal, the overlap's width along the
tangent, the boundary edge nearest to the contact point, the lightest node the area gradient
loads, and the convexity test that decides which element clips the other. The polygon is the
tagged output of pdfem.kernels.overlap (A is the clip subject, T_SRC >= 0 edges lie on A, T_SRC
< 0 on B).
"""

import numpy as np
from numba import njit

from pdfem.kernels.overlap import T_SRC

# Nodes of a contact: four of A, then four of B
NNOD = 8


@njit(cache=True)
def pair_normal(ox, oy, otag, k, ebnd, a, b):
    """Unit normal from A into B from the boundary-edge normal sums (module docstring)."""
    nx = 0.0
    ny = 0.0
    ax = 0.0
    ay = 0.0
    for i in range(k):
        i1 = i + 1 if i + 1 < k else 0
        # Outward normal x length of the overlap edge i -> i+1
        ex = oy[i1] - oy[i]
        ey = ox[i] - ox[i1]
        src = otag[i, T_SRC]
        if src >= 0:
            ax += ex
            ay += ey
            if ebnd[a, src] != 0:
                nx += ex
                ny += ey
        elif ebnd[b, -1 - src] != 0:
            nx -= ex
            ny -= ey
    # Fall back on A's whole part of the overlap boundary (topologically from A into B)
    if nx * ax + ny * ay <= 0.0:
        nx = ax
        ny = ay
    r = np.sqrt(nx * nx + ny * ny)
    if r == 0.0:
        return 0.0, 0.0
    return nx / r, ny / r


@njit(cache=True)
def area_gradient(ox, oy, otag, k, xa, xb, g):
    """dA/dx of the overlap area A of the tagged polygon (ox, oy, otag)[:k] (module docstring).

    xa (4, 2): element A (the clip subject, T_SRC >= 0 edges); xb (4, 2): element B (T_SRC < 0
    edges; ignored when xb.shape[0] == 0, a wall). g (8, 2) receives dA/dx of A's nodes in rows
    0-3 and of B's in rows 4-7. Returns (gax, gay): the sum of A's rows (dA for a translation
    of A).
    """
    for r in range(NNOD):
        g[r, 0] = 0.0
        g[r, 1] = 0.0
    for i in range(k):
        i1 = i + 1 if i + 1 < k else 0
        src = otag[i, T_SRC]
        # Outward normal x length of the overlap edge, and its midpoint
        ex = oy[i1] - oy[i]
        ey = ox[i] - ox[i1]
        mx = 0.5 * (ox[i] + ox[i1])
        my = 0.5 * (oy[i] + oy[i1])
        if src >= 0:
            j = src
            j1 = j + 1 if j + 1 < 4 else 0
            dx = xa[j1, 0] - xa[j, 0]
            dy = xa[j1, 1] - xa[j, 1]
            s = ((mx - xa[j, 0]) * dx + (my - xa[j, 1]) * dy) / (dx * dx + dy * dy)
            r0 = j
            r1 = j1
        else:
            if xb.shape[0] == 0:
                continue
            j = -1 - src
            j1 = j + 1 if j + 1 < 4 else 0
            dx = xb[j1, 0] - xb[j, 0]
            dy = xb[j1, 1] - xb[j, 1]
            s = ((mx - xb[j, 0]) * dx + (my - xb[j, 1]) * dy) / (dx * dx + dy * dy)
            r0 = 4 + j
            r1 = 4 + j1
        # A segment past its edge's end (a clip polygon that is not convex) loads the end node
        s = min(max(s, 0.0), 1.0)
        # The edge's linear shape functions at the midpoint (exact: the sweep is linear in s)
        g[r0, 0] += (1.0 - s) * ex
        g[r0, 1] += (1.0 - s) * ey
        g[r1, 0] += s * ex
        g[r1, 1] += s * ey
    gax = 0.0
    gay = 0.0
    for r in range(4):
        gax += g[r, 0]
        gay += g[r, 1]
    return gax, gay


@njit(cache=True)
def swap_sides(g):
    """Exchange rows 0-3 and 4-7 of g (8, 2) in place; return the new sum of rows 0-3."""
    sx = 0.0
    sy = 0.0
    for r in range(4):
        for c in range(2):
            t = g[r, c]
            g[r, c] = g[4 + r, c]
            g[4 + r, c] = t
        sx += g[r, 0]
        sy += g[r, 1]
    return sx, sy


@njit(cache=True)
def is_convex(xe):
    """True when the CCW quad xe (4, 2) is strictly convex (every corner turns left)."""
    for k in range(4):
        k1 = k + 1 if k + 1 < 4 else 0
        k2 = k1 + 1 if k1 + 1 < 4 else 0
        cr = ((xe[k1, 0] - xe[k, 0]) * (xe[k2, 1] - xe[k1, 1])
              - (xe[k1, 1] - xe[k, 1]) * (xe[k2, 0] - xe[k1, 0]))
        if not cr > 0.0:
            return False
    return True


@njit(cache=True)
def loaded_mass(g, nod, m, r0):
    """Smallest lumped mass of the nodes nod[r0:r0 + 4] that the area gradient g loads (inf
    when none: a rigid side)."""
    mm = np.inf
    for r in range(r0, r0 + 4):
        if nod[r] >= 0 and (g[r, 0] != 0.0 or g[r, 1] != 0.0):
            mm = min(mm, m[nod[r]])
    return mm


@njit(cache=True)
def overlap_width(ox, oy, k, tx, ty):
    """Extent of the overlap polygon along the unit tangent (tx, ty)."""
    lo = 0.0
    hi = 0.0
    # Coordinates relative to vertex 0 (the overlap is tiny next to |x|)
    for i in range(1, k):
        s = (ox[i] - ox[0]) * tx + (oy[i] - oy[0]) * ty
        lo = min(lo, s)
        hi = max(hi, s)
    return hi - lo


@njit(cache=True)
def nearest_edge(xe, ebnd, e, cx, cy):
    """Boundary edge of element e nearest to c and the parameter s in [0, 1] of c's projection.

    Returns (edge, s); edge = -1 when e has no boundary edge. The lowest edge index wins ties.
    """
    best = np.inf
    kb = -1
    sb = 0.0
    for k in range(4):
        if ebnd[e, k] == 0:
            continue
        k1 = (k + 1) % 4
        dx = xe[k1, 0] - xe[k, 0]
        dy = xe[k1, 1] - xe[k, 1]
        s = ((cx - xe[k, 0]) * dx + (cy - xe[k, 1]) * dy) / (dx * dx + dy * dy)
        s = min(max(s, 0.0), 1.0)
        rx = xe[k, 0] + s * dx - cx
        ry = xe[k, 1] + s * dy - cy
        d2 = rx * rx + ry * ry
        if d2 < best:
            best = d2
            kb = k
            sb = s
    return kb, sb
