"""Geometry of a contact's overlap polygon (pdfem.kernels.contact): the exact gradient of its area
with respect to the nodes of the two elements, the contact normal, the overlap's width along the
tangent, the boundary edge nearest to the contact point, the lightest node the area gradient
loads, and the convexity test and split that keep the clip polygon convex. The polygon is the
tagged output of pdfem.kernels.overlap (A is the clip subject, T_SRC >= 0 edges lie on A, T_SRC
< 0 on B).

pair_overlap and the small helpers it calls on every element pair are inlined into the caller
(``inline="always"``): called, they took the tuples of clip buffers and results through numba's
calling convention, a quarter of the contact time of a settled bed (bit-identical either way).
"""

import numpy as np
from numba import njit

from pdfem.kernels.overlap import (
    K_X,
    OV_INSIDE,
    OV_NONE,
    OV_OK,
    OV_OVERFLOW,
    SLIVER,
    T_EQ,
    T_KIND,
    T_SRC,
    _bbox_scale2,
    clip_convex,
    polygon_area_centroid,
    quad_overlap_area,
)

# Nodes of a contact: four of A, then four of B
NNOD = 8


@njit(cache=True, inline="always")
def normal_sums(ox, oy, otag, k, ebnd, a, b, qmap, acc):
    """Add to acc (4,) the boundary-edge normal sums of the polygon (module docstring of
    contact.py): acc[0:2] += N_A - N_B over grain-boundary edges, acc[2:4] += the sum over all of
    A's overlap edges. Clip edge j lies on B's edge qmap[j] (-1: not on B's boundary)."""
    for i in range(k):
        i1 = i + 1 if i + 1 < k else 0
        # Outward normal x length of the overlap edge i -> i+1
        ex = oy[i1] - oy[i]
        ey = ox[i] - ox[i1]
        src = otag[i, T_SRC]
        if src >= 0:
            acc[2] += ex
            acc[3] += ey
            if ebnd[a, src] != 0:
                acc[0] += ex
                acc[1] += ey
        else:
            e = qmap[-1 - src]
            if e >= 0 and ebnd[b, e] != 0:
                acc[0] -= ex
                acc[1] -= ey


@njit(cache=True, inline="always")
def unit_normal(acc):
    """Unit normal from A into B from normal_sums; A's whole part of the overlap boundary
    (topologically from A into B) when the boundary-edge sum vanishes or points backwards."""
    nx = acc[0]
    ny = acc[1]
    if nx * acc[2] + ny * acc[3] <= 0.0:
        nx = acc[2]
        ny = acc[3]
    r = np.sqrt(nx * nx + ny * ny)
    if r == 0.0:
        return 0.0, 0.0
    return nx / r, ny / r


@njit(cache=True)
def area_gradient(ox, oy, otag, k, xa, xb, qmap, g):
    """Add dA/dx of the area of the tagged polygon (ox, oy, otag)[:k] to g (module docstring).

    xa (4, 2): element A (the clip subject, T_SRC >= 0 edges); xb (4, 2): element B, whose edge
    qmap[j] clip edge j lies on (T_SRC = -1 - j; -1 in qmap: a line inside B, no node moves it;
    xb.shape[0] == 0: a wall). g (8, 2) collects A's nodes in rows 0-3 and B's in rows 4-7.
    """
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
            if xb.shape[0] == 0 or qmap[-1 - src] < 0:
                continue
            j = qmap[-1 - src]
            j1 = j + 1 if j + 1 < 4 else 0
            dx = xb[j1, 0] - xb[j, 0]
            dy = xb[j1, 1] - xb[j, 1]
            s = ((mx - xb[j, 0]) * dx + (my - xb[j, 1]) * dy) / (dx * dx + dy * dy)
            r0 = 4 + j
            r1 = 4 + j1
        # Rounding can put a midpoint a hair past its edge's end
        s = min(max(s, 0.0), 1.0)
        # The edge's linear shape functions at the midpoint (exact: the sweep is linear in s)
        g[r0, 0] += (1.0 - s) * ex
        g[r0, 1] += (1.0 - s) * ey
        g[r1, 0] += s * ex
        g[r1, 1] += s * ey


@njit(cache=True, inline="always")
def side_sum(g, r0):
    """Sum of rows r0 .. r0 + 3 of g (8, 2): dA for a translation of that side."""
    sx = 0.0
    sy = 0.0
    for r in range(r0, r0 + 4):
        sx += g[r, 0]
        sy += g[r, 1]
    return sx, sy


@njit(cache=True)
def split_quad(xb, t1, t2, m1, m2):
    """Split the non-convex CCW quad xb (4, 2) into two triangles t1, t2 (3, 2) along the
    diagonal from its reflex corner; m1, m2 (3,) get the B edge each triangle edge lies on (-1:
    the diagonal). Returns False when the quad has no reflex corner or a triangle is not CCW
    (a self-intersecting quad)."""
    r = -1
    for v in range(4):
        vp = v - 1 if v > 0 else 3
        vn = v + 1 if v < 3 else 0
        cr = ((xb[v, 0] - xb[vp, 0]) * (xb[vn, 1] - xb[v, 1])
              - (xb[v, 1] - xb[vp, 1]) * (xb[vn, 0] - xb[v, 0]))
        if not cr > 0.0:
            r = v
            break
    if r < 0:
        return False
    for i in range(3):
        # Triangle 1: corners r, r+1, r+2; triangle 2: r+2, r+3, r
        c1 = (r + i) % 4
        c2 = (r + 2 + i) % 4
        t1[i, 0] = xb[c1, 0]
        t1[i, 1] = xb[c1, 1]
        t2[i, 0] = xb[c2, 0]
        t2[i, 1] = xb[c2, 1]
    m1[0] = r
    m1[1] = (r + 1) % 4
    m1[2] = -1
    m2[0] = (r + 2) % 4
    m2[1] = (r + 3) % 4
    m2[2] = -1
    for t in (t1, t2):
        cr = ((t[1, 0] - t[0, 0]) * (t[2, 1] - t[0, 1])
              - (t[1, 1] - t[0, 1]) * (t[2, 0] - t[0, 0]))
        if not cr > 0.0:
            return False
    return True


@njit(cache=True, inline="always")
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


@njit(cache=True, inline="always")
def overlap_extent(ox, oy, k, tx, ty, x0, y0, lohi):
    """Widen lohi (2,) to the extent of the polygon (ox, oy)[:k] along the unit tangent
    (tx, ty), measured from the point (x0, y0) near it (the overlap is tiny next to |x|)."""
    for i in range(k):
        s = (ox[i] - x0) * tx + (oy[i] - y0) * ty
        lohi[0] = min(lohi[0], s)
        lohi[1] = max(lohi[1], s)


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


@njit(cache=True)
def _real_crossings(ox, oy, otag, k, qmap, st):
    """Track crossings of A's boundary with B's (clip lines that are B edges) in st (4,):
    st[0] = count seen (0, 1, or 2 = two distinct points), st[1:3] = the first one."""
    for i in range(k):
        if st[0] >= 2.0 or otag[i, T_KIND] != K_X or qmap[otag[i, T_EQ]] < 0:
            continue
        if st[0] == 0.0:
            st[0] = 1.0
            st[1] = ox[i]
            st[2] = oy[i]
        elif ox[i] != st[1] or oy[i] != st[2]:
            st[0] = 2.0


@njit(cache=True)
def alloc_overlap_work():
    """Scratch arrays of pair_overlap, allocated once per kernel call (not per pair)."""
    return (np.empty(2), np.arange(4), np.empty((3, 2)), np.empty((3, 2)), np.empty(3, np.int64),
            np.empty(3, np.int64), np.empty(3))


@njit(cache=True, inline="always")
def pair_overlap(xa, xb, ebnd, a, b, buf, buf2, work, g, acc):
    """Overlap of elements A (xa) and B (xb), its area gradient added to g (8, 2) (zeroed here)
    and its normal sums in acc (4,). B clips A when B is convex; otherwise B is split into two
    triangles along the diagonal from its reflex corner and each clips A (the clip needs a convex
    clip polygon; A as the subject may have any shape). The diagonal's overlap edges are not on
    B's boundary: they get no force, and the two pieces' shares of them cancel in the area.

    buf, buf2: (ox, oy, otag, wx, wy, wtag) clip buffers (alloc_clip_buffers); work: scratch
    (alloc_overlap_work). Returns (status,
    area, cx, cy, nx, ny, width): status as quad_overlap_area; the unit normal from A into B and
    the width along the tangent (zero unless status is OV_OK).
    """
    ox, oy, otag, wx, wy, wtag = buf
    ox2, oy2, otag2, _, _, _ = buf2
    lohi, q4, t1, t2, m1, m2, st = work
    for r in range(8):
        g[r, 0] = 0.0
        g[r, 1] = 0.0
    for i in range(4):
        acc[i] = 0.0
    lohi[0] = 0.0
    lohi[1] = 0.0
    if is_convex(xb):
        st, area, cx, cy, k = quad_overlap_area(xa, xb, ox, oy, otag, wx, wy, wtag)
        if st != OV_OK:
            return st, area, cx, cy, 0.0, 0.0, 0.0
        normal_sums(ox, oy, otag, k, ebnd, a, b, q4, acc)
        area_gradient(ox, oy, otag, k, xa, xb, q4, g)
        nx, ny = unit_normal(acc)
        overlap_extent(ox, oy, k, -ny, nx, ox[0], oy[0], lohi)
        return OV_OK, area, cx, cy, nx, ny, lohi[1] - lohi[0]
    # Two convex pieces of B
    if not split_quad(xb, t1, t2, m1, m2):
        return OV_INSIDE, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0
    k1 = clip_convex(xa, 4, t1, 3, ox, oy, otag, wx, wy, wtag)
    k2 = clip_convex(xa, 4, t2, 3, ox2, oy2, otag2, wx, wy, wtag)
    if k1 < 0 or k2 < 0:
        return OV_OVERFLOW, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0
    a1, c1x, c1y = polygon_area_centroid(ox, oy, k1)
    a2, c2x, c2y = polygon_area_centroid(ox2, oy2, k2)
    a1 = max(a1, 0.0)
    a2 = max(a2, 0.0)
    area = a1 + a2
    if area <= SLIVER * _bbox_scale2(xa):
        return OV_NONE, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0
    cx = (a1 * c1x + a2 * c2x) / area
    cy = (a1 * c1y + a2 * c2y) / area
    st[:] = 0.0
    _real_crossings(ox, oy, otag, k1, m1, st)
    _real_crossings(ox2, oy2, otag2, k2, m2, st)
    if st[0] < 2.0:
        return OV_INSIDE, area, cx, cy, 0.0, 0.0, 0.0
    normal_sums(ox, oy, otag, k1, ebnd, a, b, m1, acc)
    normal_sums(ox2, oy2, otag2, k2, ebnd, a, b, m2, acc)
    area_gradient(ox, oy, otag, k1, xa, xb, m1, g)
    area_gradient(ox2, oy2, otag2, k2, xa, xb, m2, g)
    nx, ny = unit_normal(acc)
    overlap_extent(ox, oy, k1, -ny, nx, cx, cy, lohi)
    overlap_extent(ox2, oy2, k2, -ny, nx, cx, cy, lohi)
    return OV_OK, area, cx, cy, nx, ny, lohi[1] - lohi[0]
