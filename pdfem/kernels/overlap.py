"""Overlap geometry of two convex polygons, or of a polygon and a half-plane (report sec. 5).

The overlap of element A (subject polygon P) and element B (clip polygon Q) is found by
Sutherland-Hodgman clipping of P by the edge lines of Q. Every output vertex carries a tag row
``tag[k, :]`` (int64, columns below):

- ``T_KIND``: ``K_P`` an original vertex of P, ``K_Q`` a vertex of Q (or of the wall line),
  ``K_X`` a crossing of a P edge with a Q edge (the two element boundaries cross there);
- ``T_EP``: the P edge a crossing lies on (vertex index for ``K_P``, -1 for ``K_Q``);
- ``T_EQ``: the Q edge (clip line) a crossing or Q vertex lies on (-1 for ``K_P``);
- ``T_SRC``: the boundary the polygon edge from vertex k to k+1 lies on: P edge i -> i >= 0,
  Q edge j -> -1 - j.

``T_SRC`` is what makes the contact normal robust: the sum over overlap edges lying on A's boundary
of (outward normal x length) points from A into B, whatever the shape of the overlap (for the usual
lens with two crossings c1 -> c2 it is exactly the chord rotated clockwise).

Geometry convention: polygons are counter-clockwise; the outward normal of a CCW edge (dx, dy) is
(dy, -dx) ("rotated clockwise"). A wall is the half-plane {p : n.(p - p0) < 0} behind the point p0
with the unit normal n pointing out of the wall into the domain (towards the grains).

Clip buffers (alloc_clip_buffers) are three arrays of NSLOT slots: vertex coordinates px, py
(NSLOT, MAXV) and tags pt (NSLOT, MAXV, NTAG). A clip ping-pongs between two slots, s0 and
s0 + 1, and leaves its polygon in slot s0; the public functions leave theirs in slot 0. The
per-pair functions are inlined into the contact kernels (``inline="always"``) and take the
three arrays and slot numbers, never one of several arrays chosen by a branch: numba counts
references of every array passed through a call, which on a settled bed cost several times
the clip's arithmetic.

The broad phase that feeds the clipping (element boxes, candidate pairs) is in
:mod:`pdfem.kernels.broad_phase`.
"""

import numpy as np
from numba import njit

# Capacity of a slot: P (4) clipped by 4 lines has <= 8 vertices, plus degenerate slack
MAXV = 16
# Slots of the clip buffers: two clips kept side by side (a non-convex B's two pieces)
NSLOT = 4
NTAG = 4
T_KIND = 0
T_EP = 1
T_EQ = 2
T_SRC = 3
K_P = 0
K_Q = 1
K_X = 2

# Status codes of quad_overlap / halfplane_overlap
OV_OK = 0  # positive overlap with a well-defined chord
OV_NONE = 1  # no overlap (area zero or a rounding-level sliver)
OV_INSIDE = 2  # positive area but < 2 distinct crossings: one element inside the other (guard)
OV_OVERFLOW = 3  # clip buffers too small (guard, cannot happen for convex quads)

# Overlaps below this fraction of the squared bbox extent of A are rounding slivers: no contact
SLIVER = 1e-14


@njit(cache=True)
def alloc_clip_buffers():
    """Return (px, py, pt): the clip buffers (module docstring)."""
    px = np.zeros((NSLOT, MAXV))
    py = np.zeros((NSLOT, MAXV))
    pt = np.zeros((NSLOT, MAXV, NTAG), dtype=np.int64)
    return px, py, pt


@njit(cache=True)
def clip_halfplane(px, py, pt, s, nin, x0, y0, nx, ny, line, d):
    """One Sutherland-Hodgman step: keep the part of the polygon in slot s (nin vertices) where
    nx*(x - x0) + ny*(y - y0) <= 0, into slot d. ``line`` is the clip-line id stored in the tags
    (Q edge index).

    Returns the output vertex count (0 when nothing is left, -1 on overflow).
    """
    k = 0
    if nin == 0:
        return 0
    # Walk the edges S -> E of the input polygon, starting with the closing edge
    js = nin - 1
    ss = nx * (px[s, js] - x0) + ny * (py[s, js] - y0)
    for je in range(nin):
        se = nx * (px[s, je] - x0) + ny * (py[s, je] - y0)
        src = pt[s, js, T_SRC]
        # A crossing of a P edge with this line is a boundary crossing, else it is a Q vertex
        if src >= 0:
            kind = K_X
            ep = src
        else:
            kind = K_Q
            ep = -1
        if se <= 0.0:
            if ss > 0.0:
                # Entering: intersection point, then E; the edge out of it continues S -> E
                if k >= MAXV:
                    return -1
                t = ss / (ss - se)
                px[d, k] = px[s, js] + t * (px[s, je] - px[s, js])
                py[d, k] = py[s, js] + t * (py[s, je] - py[s, js])
                pt[d, k, T_KIND] = kind
                pt[d, k, T_EP] = ep
                pt[d, k, T_EQ] = line
                pt[d, k, T_SRC] = src
                k += 1
            if k >= MAXV:
                return -1
            px[d, k] = px[s, je]
            py[d, k] = py[s, je]
            for c in range(NTAG):
                pt[d, k, c] = pt[s, je, c]
            k += 1
        elif ss <= 0.0:
            # Leaving: intersection point; the edge out of it runs along the clip line
            if k >= MAXV:
                return -1
            t = ss / (ss - se)
            px[d, k] = px[s, js] + t * (px[s, je] - px[s, js])
            py[d, k] = py[s, js] + t * (py[s, je] - py[s, js])
            pt[d, k, T_KIND] = kind
            pt[d, k, T_EP] = ep
            pt[d, k, T_EQ] = line
            pt[d, k, T_SRC] = -1 - line
            k += 1
        js = je
        ss = se
    return k


@njit(cache=True)
def load_subject(pxy, n, px, py, pt, s):
    """Copy subject polygon P = pxy[:n] (rows x, y) into slot s (vertex i, edge i -> i+1 has
    source i)."""
    for i in range(n):
        px[s, i] = pxy[i, 0]
        py[s, i] = pxy[i, 1]
        pt[s, i, T_KIND] = K_P
        pt[s, i, T_EP] = i
        pt[s, i, T_EQ] = -1
        pt[s, i, T_SRC] = i


@njit(cache=True)
def clip_into(pxy, n, qxy, m, px, py, pt, s0):
    """Intersection of convex CCW polygons P = pxy[:n] and Q = qxy[:m] (rows x, y), left in
    slot s0 (slot s0 + 1 is work). Returns the vertex count (0: empty, -1: overflow)."""
    if n > MAXV:
        return -1
    # Ping-pong between the two slots; start so that the last step writes into s0
    cur = s0 if m & 1 == 0 else s0 + 1
    load_subject(pxy, n, px, py, pt, cur)
    k = n
    for j in range(m):
        # Next vertex of Q (a compare, not an integer division)
        j1 = j + 1 if j + 1 < m else 0
        # Outward normal of CCW edge j of Q (not normalised: only signs and ratios matter)
        nx = qxy[j1, 1] - qxy[j, 1]
        ny = qxy[j, 0] - qxy[j1, 0]
        nxt = 2 * s0 + 1 - cur
        k = clip_halfplane(px, py, pt, cur, k, qxy[j, 0], qxy[j, 1], nx, ny, j, nxt)
        cur = nxt
        if k <= 0:
            return k
    return k


@njit(cache=True)
def clip_convex(pxy, n, qxy, m, px, py, pt):
    """clip_into slot 0: the intersection of convex CCW polygons P = pxy[:n] and Q = qxy[:m]
    (the tagged result in slot 0 of (px, py, pt), the module docstring); returns its vertex
    count (0: empty, -1: buffer overflow)."""
    return clip_into(pxy, n, qxy, m, px, py, pt, 0)


@njit(cache=True)
def polygon_area_centroid(px, py, s, k):
    """Area and centroid of the polygon in slot s (k vertices, CCW positive), fanned from
    vertex 0."""
    if k < 3:
        return 0.0, 0.0, 0.0
    a2 = 0.0
    sx = 0.0
    sy = 0.0
    # Triangles (v0, vi, vi+1) in coordinates relative to v0 (less cancellation)
    for i in range(1, k - 1):
        ax = px[s, i] - px[s, 0]
        ay = py[s, i] - py[s, 0]
        bx = px[s, i + 1] - px[s, 0]
        by = py[s, i + 1] - py[s, 0]
        c = ax * by - ay * bx
        a2 += c
        sx += c * (ax + bx)
        sy += c * (ay + by)
    if a2 == 0.0:
        return 0.0, px[s, 0], py[s, 0]
    return 0.5 * a2, px[s, 0] + sx / (3.0 * a2), py[s, 0] + sy / (3.0 * a2)


@njit(cache=True)
def boundary_normal_sum(px, py, pt, k):
    """Sum over the overlap edges (slot 0, k vertices) lying on P's boundary of (outward normal
    x length).

    It points from P into Q; for two crossings c1 -> c2 (CCW along P's part) it is exactly
    (c2 - c1) rotated clockwise, i.e. the chord's normal scaled by the chord length.
    """
    sx = 0.0
    sy = 0.0
    for i in range(k):
        if pt[0, i, T_SRC] >= 0:
            i1 = i + 1 if i + 1 < k else 0
            sx += py[0, i1] - py[0, i]
            sy -= px[0, i1] - px[0, i]
    return sx, sy


@njit(cache=True)
def crossing_chord(px, py, pt, k):
    """Chord of the overlap in slot 0: the two boundary crossing points farthest apart.

    Returns (n_cross, c1x, c1y, c2x, c2y), ordered so that (c2 - c1) rotated clockwise points
    from P into Q (sign taken from boundary_normal_sum; with exactly two crossings that sum *is*
    the rotated chord). With fewer than 2 distinct crossings the chord has zero length.
    """
    ncr = 0
    c1x = 0.0
    c1y = 0.0
    c2x = 0.0
    c2y = 0.0
    best = -1.0
    # Farthest pair among the crossing vertices; the first pair found wins ties
    for i in range(k):
        if pt[0, i, T_KIND] != K_X:
            continue
        ncr += 1
        for j in range(i + 1, k):
            if pt[0, j, T_KIND] != K_X:
                continue
            dx = px[0, j] - px[0, i]
            dy = py[0, j] - py[0, i]
            d2 = dx * dx + dy * dy
            if d2 > best:
                best = d2
                c1x = px[0, i]
                c1y = py[0, i]
                c2x = px[0, j]
                c2y = py[0, j]
    # Orient the chord so that its clockwise normal points from P into Q
    sx, sy = boundary_normal_sum(px, py, pt, k)
    if (c2y - c1y) * sx - (c2x - c1x) * sy < 0.0:
        c1x, c1y, c2x, c2y = c2x, c2y, c1x, c1y
    return ncr, c1x, c1y, c2x, c2y


@njit(cache=True)
def classify(px, py, pt, k, scale2):
    """Area, centroid and chord of the clipped polygon in slot 0, with the status code of
    quad_overlap."""
    if k < 0:
        return OV_OVERFLOW, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0
    area, cx, cy = polygon_area_centroid(px, py, 0, k)
    if area <= SLIVER * scale2:
        return OV_NONE, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0
    ncr, c1x, c1y, c2x, c2y = crossing_chord(px, py, pt, k)
    status = OV_OK
    if ncr < 2 or (c1x == c2x and c1y == c2y):
        status = OV_INSIDE
    return status, area, cx, cy, c1x, c1y, c2x, c2y


@njit(cache=True)
def bbox_scale2(xa):
    """Squared largest bbox extent of the quad xa (4, 2)."""
    ex = max(xa[0, 0], xa[1, 0], xa[2, 0], xa[3, 0]) - min(xa[0, 0], xa[1, 0], xa[2, 0], xa[3, 0])
    ey = max(xa[0, 1], xa[1, 1], xa[2, 1], xa[3, 1]) - min(xa[0, 1], xa[1, 1], xa[2, 1], xa[3, 1])
    e = max(ex, ey)
    return e * e


@njit(cache=True)
def outside_edge(xa, xb):
    """True when every corner of xb lies strictly outside one edge line of the CCW quad xa
    (n.(p - a_j) > 0 with the clip's own formula, clip_halfplane)."""
    for j in range(4):
        j1 = (j + 1) % 4
        # Outward normal of edge j, and the corners' signed distances (scaled)
        nx = xa[j1, 1] - xa[j, 1]
        ny = xa[j, 0] - xa[j1, 0]
        out = True
        for i in range(4):
            if nx * (xb[i, 0] - xa[j, 0]) + ny * (xb[i, 1] - xa[j, 1]) <= 0.0:
                out = False
                break
        if out:
            return True
    return False


@njit(cache=True)
def quad_overlap(xa, xb, px, py, pt):
    """Overlap of convex CCW quads xa (4, 2) [element A] and xb (4, 2) [element B].

    Returns (status, area, cx, cy, c1x, c1y, c2x, c2y, k): overlap area, its centroid, the chord
    endpoints (the two crossings of the element boundaries farthest apart) oriented so that the
    chord's clockwise normal (c2y - c1y, c1x - c2x)/|c2 - c1| points from A into B, and the vertex
    count k of the tagged overlap polygon left in slot 0. Status: OV_OK; OV_NONE (area 0, or a
    sliver below SLIVER * extent(A)^2: no contact); OV_INSIDE (positive area but fewer than 2
    distinct crossings: one element contains the other, the caller treats it as an error);
    OV_OVERFLOW.
    """
    st, area, cx, cy, k = quad_overlap_into(xa, xb, px, py, pt, 0)
    if st != OV_OK and st != OV_INSIDE:
        return st, area, cx, cy, 0.0, 0.0, 0.0, 0.0, k
    # The chord, oriented from A into B
    _, c1x, c1y, c2x, c2y = crossing_chord(px, py, pt, k)
    return st, area, cx, cy, c1x, c1y, c2x, c2y, k


@njit(cache=True)
def _distinct_crossings(px, py, pt, s, k):
    """True when the polygon in slot s has two crossing vertices at different points (the test
    of classify's chord, without finding the farthest pair or orienting it)."""
    first = -1
    for i in range(k):
        if pt[s, i, T_KIND] != K_X:
            continue
        if first < 0:
            first = i
        elif px[s, i] != px[s, first] or py[s, i] != py[s, first]:
            return True
    return False


@njit(cache=True)
def quad_overlap_into(xa, xb, px, py, pt, s0):
    """quad_overlap without the chord, the polygon left in slot s0: (status, area, cx, cy, k),
    the same values. For the contact kernel, which needs the status, the overlap polygon and
    its centroid.
    """
    # Early out: A wholly outside an edge line of B, so the first clip by that line would
    # leave nothing (exactly what the clip finds; the converse test is not used: it is only
    # valid for a convex A, and a distorted element need not be convex)
    if outside_edge(xb, xa):
        return OV_NONE, 0.0, 0.0, 0.0, 0
    k = clip_into(xa, 4, xb, 4, px, py, pt, s0)
    if k < 0:
        return OV_OVERFLOW, 0.0, 0.0, 0.0, k
    area, cx, cy = polygon_area_centroid(px, py, s0, k)
    if area <= SLIVER * bbox_scale2(xa):
        return OV_NONE, 0.0, 0.0, 0.0, k
    if not _distinct_crossings(px, py, pt, s0, k):
        return OV_INSIDE, area, cx, cy, k
    return OV_OK, area, cx, cy, k


@njit(cache=True)
def quad_overlap_area(xa, xb, px, py, pt):
    """quad_overlap_into slot 0."""
    return quad_overlap_into(xa, xb, px, py, pt, 0)


@njit(cache=True)
def halfplane_into(xa, p0x, p0y, nx, ny, px, py, pt):
    """halfplane_overlap, inlined into the contact kernels."""
    load_subject(xa, 4, px, py, pt, 1)
    k = clip_halfplane(px, py, pt, 1, 4, p0x, p0y, nx, ny, 0, 0)
    st, area, cx, cy, c1x, c1y, c2x, c2y = classify(px, py, pt, k, bbox_scale2(xa))
    return st, area, cx, cy, c1x, c1y, c2x, c2y, k


@njit(cache=True)
def halfplane_overlap(xa, p0x, p0y, nx, ny, px, py, pt):
    """Overlap of the convex CCW quad xa (4, 2) with the wall {p : n.(p - p0) < 0}.

    n = (nx, ny) is the wall's unit normal pointing out of the wall into the domain, p0 =
    (p0x, p0y) a point of the wall line. Returns the same tuple as quad_overlap plus the vertex
    count k (the polygon in slot 0); the chord lies on the wall line and is oriented so that
    its clockwise normal is -n (from the element into the wall). OV_INSIDE means the whole
    element is behind the wall. Crossings carry T_EQ = 0 (the wall line).
    """
    return halfplane_into(xa, p0x, p0y, nx, ny, px, py, pt)
