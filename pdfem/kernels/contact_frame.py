"""Geometry of a contact's overlap polygon (pdfem.kernels.contact): the exact gradient of its area
with respect to the nodes of the two elements, the contact normal, the overlap's width along the
tangent, the boundary edge nearest to the contact point, the lightest node the area gradient
loads, and the convexity test and split that keep the clip polygon convex. The polygon is the
tagged output of pdfem.kernels.overlap in a slot of the clip buffers (A is the clip subject,
T_SRC >= 0 edges lie on A, T_SRC < 0 on B).

Each function does a whole step of a pair's geometry and returns its sums as scalars: numba
counts references to every array passed through a call, so many small calls per pair cost
more than the arithmetic (see pdfem.kernels.overlap).
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
    bbox_scale2,
    clip_into,
    polygon_area_centroid,
    quad_overlap_into,
)

# Nodes of a contact: four of A, then four of B
NNOD = 8


@njit(cache=True)
def polygon_frame(px, py, pt, s, k, qmap, xa, xb, has_b, ebnd, a, b, g, n0, n1, s0, s1):
    """The overlap polygon in slot s (k vertices): its area gradient dA/dx added to g (module
    docstring of contact.py) and its normal sums added to (n0, n1, s0, s1), which are returned.

    xa (4, 2): element A (the clip subject, T_SRC >= 0 edges); xb (4, 2): element B, whose edge
    qmap[j] clip edge j lies on (T_SRC = -1 - j; -1 in qmap: a line inside B, no node moves it;
    has_b False: a wall, no B). g (8, 2) collects A's nodes in rows 0-3 and B's in rows 4-7.
    Normal sums: (n0, n1) += N_A - N_B over grain-boundary edges, (s0, s1) += the sum over
    all of A's overlap edges (both of outward normal x length).
    """
    for i in range(k):
        i1 = i + 1 if i + 1 < k else 0
        src = pt[s, i, T_SRC]
        # Outward normal x length of the overlap edge, and its midpoint
        ex = py[s, i1] - py[s, i]
        ey = px[s, i] - px[s, i1]
        mx = 0.5 * (px[s, i] + px[s, i1])
        my = 0.5 * (py[s, i] + py[s, i1])
        if src >= 0:
            s0 += ex
            s1 += ey
            if ebnd[a, src] != 0:
                n0 += ex
                n1 += ey
            j = src
            j1 = j + 1 if j + 1 < 4 else 0
            dx = xa[j1, 0] - xa[j, 0]
            dy = xa[j1, 1] - xa[j, 1]
            f = ((mx - xa[j, 0]) * dx + (my - xa[j, 1]) * dy) / (dx * dx + dy * dy)
            r0 = j
            r1 = j1
        else:
            if not has_b or qmap[-1 - src] < 0:
                continue
            j = qmap[-1 - src]
            if ebnd[b, j] != 0:
                n0 -= ex
                n1 -= ey
            j1 = j + 1 if j + 1 < 4 else 0
            dx = xb[j1, 0] - xb[j, 0]
            dy = xb[j1, 1] - xb[j, 1]
            f = ((mx - xb[j, 0]) * dx + (my - xb[j, 1]) * dy) / (dx * dx + dy * dy)
            r0 = 4 + j
            r1 = 4 + j1
        # Rounding can put a midpoint a hair past its edge's end
        f = min(max(f, 0.0), 1.0)
        # The edge's linear shape functions at the midpoint (exact: the sweep is linear in f)
        g[r0, 0] += (1.0 - f) * ex
        g[r0, 1] += (1.0 - f) * ey
        g[r1, 0] += f * ex
        g[r1, 1] += f * ey
    return n0, n1, s0, s1


@njit(cache=True)
def unit_normal(n0, n1, s0, s1):
    """Unit normal from A into B from normal_sums; A's whole part of the overlap boundary
    (topologically from A into B) when the boundary-edge sum vanishes or points backwards."""
    nx = n0
    ny = n1
    if nx * s0 + ny * s1 <= 0.0:
        nx = s0
        ny = s1
    r = np.sqrt(nx * nx + ny * ny)
    if r == 0.0:
        return 0.0, 0.0
    return nx / r, ny / r


@njit(cache=True)
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
def overlap_extent(px, py, s, k, tx, ty, x0, y0, lo, hi):
    """(lo, hi) widened to the extent of the polygon in slot s (k vertices) along the unit
    tangent (tx, ty), measured from the point (x0, y0) near it (the overlap is tiny next to
    |x|)."""
    for i in range(k):
        f = (px[s, i] - x0) * tx + (py[s, i] - y0) * ty
        lo = min(lo, f)
        hi = max(hi, f)
    return lo, hi


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
def _real_crossings(px, py, pt, s, k, qmap, cnt, fx, fy):
    """Crossings of A's boundary with B's (clip lines that are B edges) in the polygon in slot
    s, added to (cnt, fx, fy): cnt the count seen (0, 1, or 2 = two distinct points), (fx, fy)
    the first one. Returns the updated triple."""
    for i in range(k):
        if cnt >= 2.0 or pt[s, i, T_KIND] != K_X or qmap[pt[s, i, T_EQ]] < 0:
            continue
        if cnt == 0.0:
            cnt = 1.0
            fx = px[s, i]
            fy = py[s, i]
        elif px[s, i] != fx or py[s, i] != fy:
            cnt = 2.0
    return cnt, fx, fy


@njit(cache=True)
def alloc_overlap_work():
    """Scratch arrays of pair_overlap: q4 (the identity map of B's edges), tri (2, 3, 2) and
    tmap (2, 3) (a split B's triangles and their edge maps), allocated once per kernel call
    (not per pair)."""
    return np.arange(4), np.empty((2, 3, 2)), np.empty((2, 3), np.int64)


@njit(cache=True)
def _split_clip(xa, xb, px, py, pt, tri, tmap):
    """Split the non-convex B (split_quad) into tri, tmap and clip A by each triangle into
    slots 0 and 2; returns (split done, k1, k2)."""
    t1 = tri[0]
    t2 = tri[1]
    if not split_quad(xb, t1, t2, tmap[0], tmap[1]):
        return False, 0, 0
    return True, clip_into(xa, 4, t1, 3, px, py, pt, 0), clip_into(xa, 4, t2, 3, px, py, pt, 2)


@njit(cache=True)
def pair_overlap(xa, xb, ebnd, a, b, px, py, pt, q4, tri, tmap, g):
    """Overlap of elements A (xa) and B (xb), its area gradient added to g (8, 2) (zeroed here).
    B clips A when B is convex; otherwise B is split into two triangles along the diagonal from
    its reflex corner and each clips A (the clip needs a convex clip polygon; A as the subject
    may have any shape). The diagonal's overlap edges are not on B's boundary: they get no
    force, and the two pieces' shares of them cancel in the area.

    px, py, pt: clip buffers (overlap.alloc_clip_buffers; the polygon is left in slot 0, a
    split B's second piece in slot 2); q4, tri, tmap: scratch (alloc_overlap_work). Returns (status,
    area, cx, cy, nx, ny, width): status as quad_overlap_area; the unit normal from A into B and
    the width along the tangent (zero unless status is OV_OK).
    """
    for r in range(8):
        g[r, 0] = 0.0
        g[r, 1] = 0.0
    lo = 0.0
    hi = 0.0
    if is_convex(xb):
        st, area, cx, cy, k = quad_overlap_into(xa, xb, px, py, pt, 0)
        if st != OV_OK:
            return st, area, cx, cy, 0.0, 0.0, 0.0
        n0, n1, s0, s1 = polygon_frame(px, py, pt, 0, k, q4, xa, xb, True, ebnd, a, b, g, 0.0,
                                       0.0, 0.0, 0.0)
        nx, ny = unit_normal(n0, n1, s0, s1)
        lo, hi = overlap_extent(px, py, 0, k, -ny, nx, px[0, 0], py[0, 0], lo, hi)
        return OV_OK, area, cx, cy, nx, ny, hi - lo
    # Two convex pieces of B (a call, not inlined: rare, and its own two clips)
    done, k1, k2 = _split_clip(xa, xb, px, py, pt, tri, tmap)
    if not done:
        return OV_INSIDE, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0
    if k1 < 0 or k2 < 0:
        return OV_OVERFLOW, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0
    a1, c1x, c1y = polygon_area_centroid(px, py, 0, k1)
    a2, c2x, c2y = polygon_area_centroid(px, py, 2, k2)
    a1 = max(a1, 0.0)
    a2 = max(a2, 0.0)
    area = a1 + a2
    if area <= SLIVER * bbox_scale2(xa):
        return OV_NONE, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0
    cx = (a1 * c1x + a2 * c2x) / area
    cy = (a1 * c1y + a2 * c2y) / area
    m1 = tmap[0]
    m2 = tmap[1]
    cnt, fx, fy = _real_crossings(px, py, pt, 0, k1, m1, 0.0, 0.0, 0.0)
    cnt, fx, fy = _real_crossings(px, py, pt, 2, k2, m2, cnt, fx, fy)
    if cnt < 2.0:
        return OV_INSIDE, area, cx, cy, 0.0, 0.0, 0.0
    n0, n1, s0, s1 = polygon_frame(px, py, pt, 0, k1, m1, xa, xb, True, ebnd, a, b, g, 0.0,
                                   0.0, 0.0, 0.0)
    n0, n1, s0, s1 = polygon_frame(px, py, pt, 2, k2, m2, xa, xb, True, ebnd, a, b, g, n0, n1,
                                   s0, s1)
    nx, ny = unit_normal(n0, n1, s0, s1)
    lo, hi = overlap_extent(px, py, 0, k1, -ny, nx, cx, cy, lo, hi)
    lo, hi = overlap_extent(px, py, 2, k2, -ny, nx, cx, cy, lo, hi)
    return OV_OK, area, cx, cy, nx, ny, hi - lo
