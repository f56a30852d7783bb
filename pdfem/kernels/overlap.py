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

The broad phase that feeds the clipping (element boxes, candidate pairs) is in
:mod:`pdfem.kernels.broad_phase`.
"""

import numpy as np
from numba import njit

# Capacity of the clip buffers: P (4) clipped by 4 lines has <= 8 vertices, plus degenerate slack
MAXV = 16
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
    """Return (ox, oy, otag, wx, wy, wtag): output and work buffers for clip_convex."""
    ox = np.zeros(MAXV)
    oy = np.zeros(MAXV)
    otag = np.zeros((MAXV, NTAG), dtype=np.int64)
    wx = np.zeros(MAXV)
    wy = np.zeros(MAXV)
    wtag = np.zeros((MAXV, NTAG), dtype=np.int64)
    return ox, oy, otag, wx, wy, wtag


@njit(cache=True)
def _put(ox, oy, otag, k, x, y, kind, ep, eq, src):
    """Write vertex k of an output polygon; return k + 1, or -1 when the buffer is full."""
    if k < 0 or k >= ox.shape[0]:
        return -1
    ox[k] = x
    oy[k] = y
    otag[k, T_KIND] = kind
    otag[k, T_EP] = ep
    otag[k, T_EQ] = eq
    otag[k, T_SRC] = src
    return k + 1


@njit(cache=True)
def clip_halfplane(ix, iy, itag, nin, x0, y0, nx, ny, line, ox, oy, otag):
    """One Sutherland-Hodgman step: keep the part of polygon (ix, iy)[:nin] where
    nx*(x - x0) + ny*(y - y0) <= 0. ``line`` is the clip-line id stored in the tags (Q edge index).

    Returns the output vertex count (0 when nothing is left, -1 on buffer overflow).
    """
    k = 0
    if nin == 0:
        return 0
    # Walk the edges S -> E of the input polygon, starting with the closing edge
    js = nin - 1
    ss = nx * (ix[js] - x0) + ny * (iy[js] - y0)
    for je in range(nin):
        se = nx * (ix[je] - x0) + ny * (iy[je] - y0)
        src = itag[js, T_SRC]
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
                t = ss / (ss - se)
                xi = ix[js] + t * (ix[je] - ix[js])
                yi = iy[js] + t * (iy[je] - iy[js])
                k = _put(ox, oy, otag, k, xi, yi, kind, ep, line, src)
            k = _put(
                ox,
                oy,
                otag,
                k,
                ix[je],
                iy[je],
                itag[je, T_KIND],
                itag[je, T_EP],
                itag[je, T_EQ],
                itag[je, T_SRC],
            )
        elif ss <= 0.0:
            # Leaving: intersection point; the edge out of it runs along the clip line
            t = ss / (ss - se)
            xi = ix[js] + t * (ix[je] - ix[js])
            yi = iy[js] + t * (iy[je] - iy[js])
            k = _put(ox, oy, otag, k, xi, yi, kind, ep, line, -1 - line)
        if k < 0:
            return -1
        js = je
        ss = se
    return k


@njit(cache=True)
def _load_subject(pxy, n, ox, oy, otag):
    """Copy subject polygon P = pxy[:n] (rows x, y) into a tagged buffer (vertex i, edge
    i -> i+1 has source i)."""
    for i in range(n):
        ox[i] = pxy[i, 0]
        oy[i] = pxy[i, 1]
        otag[i, T_KIND] = K_P
        otag[i, T_EP] = i
        otag[i, T_EQ] = -1
        otag[i, T_SRC] = i


@njit(cache=True)
def clip_convex(pxy, n, qxy, m, ox, oy, otag, wx, wy, wtag):
    """Intersection of convex CCW polygons P = pxy[:n] and Q = qxy[:m] (rows x, y; the
    (n, 2) arrays are indexed in place: column views cost more than the clip in hot loops).

    The tagged result (see module docstring) is left in (ox, oy, otag); (wx, wy, wtag) are work
    buffers of the same size. Returns the vertex count (0: empty, -1: buffer overflow).
    """
    if n > ox.shape[0]:
        return -1
    # Ping-pong between the two buffers; start so that the last step writes into ox
    if m & 1 == 0:
        _load_subject(pxy, n, ox, oy, otag)
    else:
        _load_subject(pxy, n, wx, wy, wtag)
    k = n
    for j in range(m):
        # Next vertex of Q (a compare, not an integer division)
        j1 = j + 1 if j + 1 < m else 0
        # Outward normal of CCW edge j of Q (not normalised: only signs and ratios matter)
        nx = qxy[j1, 1] - qxy[j, 1]
        ny = qxy[j, 0] - qxy[j1, 0]
        if (m - j) & 1 == 0:
            k = clip_halfplane(ox, oy, otag, k, qxy[j, 0], qxy[j, 1], nx, ny, j, wx, wy, wtag)
        else:
            k = clip_halfplane(wx, wy, wtag, k, qxy[j, 0], qxy[j, 1], nx, ny, j, ox, oy, otag)
        if k <= 0:
            return k
    return k


@njit(cache=True)
def polygon_area_centroid(x, y, k):
    """Area and centroid of the polygon (x, y)[:k] (CCW positive), fanned from vertex 0."""
    if k < 3:
        return 0.0, 0.0, 0.0
    a2 = 0.0
    sx = 0.0
    sy = 0.0
    # Triangles (v0, vi, vi+1) in coordinates relative to v0 (less cancellation)
    for i in range(1, k - 1):
        ax = x[i] - x[0]
        ay = y[i] - y[0]
        bx = x[i + 1] - x[0]
        by = y[i + 1] - y[0]
        c = ax * by - ay * bx
        a2 += c
        sx += c * (ax + bx)
        sy += c * (ay + by)
    if a2 == 0.0:
        return 0.0, x[0], y[0]
    return 0.5 * a2, x[0] + sx / (3.0 * a2), y[0] + sy / (3.0 * a2)


@njit(cache=True)
def boundary_normal_sum(ox, oy, otag, k):
    """Sum over the overlap edges lying on P's boundary of (outward normal x length).

    It points from P into Q; for two crossings c1 -> c2 (CCW along P's part) it is exactly
    (c2 - c1) rotated clockwise, i.e. the chord's normal scaled by the chord length.
    """
    sx = 0.0
    sy = 0.0
    for i in range(k):
        if otag[i, T_SRC] >= 0:
            i1 = i + 1 if i + 1 < k else 0
            sx += oy[i1] - oy[i]
            sy -= ox[i1] - ox[i]
    return sx, sy


@njit(cache=True)
def crossing_chord(ox, oy, otag, k):
    """Chord of the overlap: the two boundary crossing points farthest apart.

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
        if otag[i, T_KIND] != K_X:
            continue
        ncr += 1
        for j in range(i + 1, k):
            if otag[j, T_KIND] != K_X:
                continue
            dx = ox[j] - ox[i]
            dy = oy[j] - oy[i]
            d2 = dx * dx + dy * dy
            if d2 > best:
                best = d2
                c1x = ox[i]
                c1y = oy[i]
                c2x = ox[j]
                c2y = oy[j]
    # Orient the chord so that its clockwise normal points from P into Q
    sx, sy = boundary_normal_sum(ox, oy, otag, k)
    if (c2y - c1y) * sx - (c2x - c1x) * sy < 0.0:
        c1x, c1y, c2x, c2y = c2x, c2y, c1x, c1y
    return ncr, c1x, c1y, c2x, c2y


@njit(cache=True)
def _classify(ox, oy, otag, k, scale2):
    """Area, centroid and chord of a clipped polygon, with the status code of quad_overlap."""
    if k < 0:
        return OV_OVERFLOW, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0
    area, cx, cy = polygon_area_centroid(ox, oy, k)
    if area <= SLIVER * scale2:
        return OV_NONE, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0
    ncr, c1x, c1y, c2x, c2y = crossing_chord(ox, oy, otag, k)
    status = OV_OK
    if ncr < 2 or (c1x == c2x and c1y == c2y):
        status = OV_INSIDE
    return status, area, cx, cy, c1x, c1y, c2x, c2y


@njit(cache=True)
def _bbox_scale2(xa):
    """Squared largest bbox extent of the quad xa (4, 2)."""
    ex = max(xa[0, 0], xa[1, 0], xa[2, 0], xa[3, 0]) - min(xa[0, 0], xa[1, 0], xa[2, 0], xa[3, 0])
    ey = max(xa[0, 1], xa[1, 1], xa[2, 1], xa[3, 1]) - min(xa[0, 1], xa[1, 1], xa[2, 1], xa[3, 1])
    e = max(ex, ey)
    return e * e


@njit(cache=True)
def _outside_edge(xa, xb):
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
def quad_overlap(xa, xb, ox, oy, otag, wx, wy, wtag):
    """Overlap of convex CCW quads xa (4, 2) [element A] and xb (4, 2) [element B].

    Returns (status, area, cx, cy, c1x, c1y, c2x, c2y, k): overlap area, its centroid, the chord
    endpoints (the two crossings of the element boundaries farthest apart) oriented so that the
    chord's clockwise normal (c2y - c1y, c1x - c2x)/|c2 - c1| points from A into B, and the vertex
    count k of the tagged overlap polygon left in (ox, oy, otag). Status: OV_OK; OV_NONE (area 0,
    or a sliver below SLIVER * extent(A)^2: no contact); OV_INSIDE (positive area but fewer than
    2 distinct crossings: one element contains the other, the caller treats it as an error);
    OV_OVERFLOW.
    """
    st, area, cx, cy, k = quad_overlap_area(xa, xb, ox, oy, otag, wx, wy, wtag)
    if st != OV_OK and st != OV_INSIDE:
        return st, area, cx, cy, 0.0, 0.0, 0.0, 0.0, k
    # The chord, oriented from A into B
    _, c1x, c1y, c2x, c2y = crossing_chord(ox, oy, otag, k)
    return st, area, cx, cy, c1x, c1y, c2x, c2y, k


@njit(cache=True)
def _distinct_crossings(ox, oy, otag, k):
    """True when the polygon has two crossing vertices at different points (the test of
    _classify's chord, without finding the farthest pair or orienting it)."""
    first = -1
    for i in range(k):
        if otag[i, T_KIND] != K_X:
            continue
        if first < 0:
            first = i
        elif ox[i] != ox[first] or oy[i] != oy[first]:
            return True
    return False


@njit(cache=True)
def quad_overlap_area(xa, xb, ox, oy, otag, wx, wy, wtag):
    """quad_overlap without the chord: (status, area, cx, cy, k), the same values.

    For the contact kernel, which needs the status, the overlap polygon and its centroid.
    """
    # Early out: A wholly outside an edge line of B, so the first clip by that line would
    # leave nothing (exactly what the clip finds; the converse test is not used: it is only
    # valid for a convex A, and a distorted element need not be convex)
    if _outside_edge(xb, xa):
        return OV_NONE, 0.0, 0.0, 0.0, 0
    k = clip_convex(xa, 4, xb, 4, ox, oy, otag, wx, wy, wtag)
    if k < 0:
        return OV_OVERFLOW, 0.0, 0.0, 0.0, k
    area, cx, cy = polygon_area_centroid(ox, oy, k)
    if area <= SLIVER * _bbox_scale2(xa):
        return OV_NONE, 0.0, 0.0, 0.0, k
    if not _distinct_crossings(ox, oy, otag, k):
        return OV_INSIDE, area, cx, cy, k
    return OV_OK, area, cx, cy, k


@njit(cache=True)
def halfplane_overlap(xa, p0, n, ox, oy, otag, wx, wy, wtag):
    """Overlap of the convex CCW quad xa (4, 2) with the wall {p : n.(p - p0) < 0}.

    n is the wall's unit normal pointing out of the wall into the domain. Returns the same tuple
    as quad_overlap plus the vertex count k; the chord lies on the wall line and is oriented so
    that its clockwise normal is -n (from the element into the wall). OV_INSIDE means the whole
    element is behind the wall. Crossings carry T_EQ = 0 (the wall line).
    """
    _load_subject(xa, 4, wx, wy, wtag)
    k = clip_halfplane(wx, wy, wtag, 4, p0[0], p0[1], n[0], n[1], 0, ox, oy, otag)
    st, area, cx, cy, c1x, c1y, c2x, c2y = _classify(ox, oy, otag, k, _bbox_scale2(xa))
    return st, area, cx, cy, c1x, c1y, c2x, c2y, k
