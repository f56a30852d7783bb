"""Polygons given by their vertex rows: distances between them, and their area inside a
horizontal slab (a packing's slices). Either orientation; the slab clip needs no convexity.
"""

import math

import numpy as np
from numba import njit

from pdfem.kernels.cell_list import around


@njit(cache=True)
def _segment_distance(px, py, ax, ay, bx, by):
    """Distance from point p to the segment a-b."""
    ex, ey = bx - ax, by - ay
    ll = ex * ex + ey * ey
    t = 0.0 if ll == 0.0 else min(max(((px - ax) * ex + (py - ay) * ey) / ll, 0.0), 1.0)
    return math.hypot(px - ax - t * ex, py - ay - t * ey)


@njit(cache=True)
def polygon_gap(pa, pb):
    """Distance between two disjoint polygons (vertex rows, absolute): the least distance of a
    vertex of either to an edge of the other."""
    best = math.inf
    for p, q in ((pa, pb), (pb, pa)):
        nq = q.shape[0]
        for m in range(p.shape[0]):
            for k in range(nq):
                k1 = k + 1 if k + 1 < nq else 0
                d = _segment_distance(p[m, 0], p[m, 1], q[k, 0], q[k, 1], q[k1, 0], q[k1, 1])
                if d < best:
                    best = d
    return best


@njit(cache=True)
def nearest_gaps(cx, cy, verts, rad, cell, start, items, nx, ny, reach, gap, near):
    """Per grain: the gap to its nearest neighbouring grain (gap[i], inf if none within the
    3 x 3 cells) and the number of neighbours closer than each distance of ``reach``
    (near[i, r])."""
    n = cx.shape[0]
    pa = np.empty_like(verts[0])
    pb = np.empty_like(verts[0])
    cells = np.empty(9, np.int64)
    for i in range(n):
        gap[i] = math.inf
        near[i, :] = 0
        for c in range(around(cell[i], nx, ny, cells)):
            k = cells[c]
            for q in range(start[k], start[k + 1]):
                j = items[q]
                if j == i or math.hypot(cx[j] - cx[i], cy[j] - cy[i]) - rad[i] - rad[j] > \
                        max(gap[i], reach[-1]):
                    continue
                for m in range(pa.shape[0]):
                    pa[m, 0], pa[m, 1] = cx[i] + verts[i, m, 0], cy[i] + verts[i, m, 1]
                    pb[m, 0], pb[m, 1] = cx[j] + verts[j, m, 0], cy[j] + verts[j, m, 1]
                d = polygon_gap(pa, pb)
                gap[i] = min(gap[i], d)
                for r in range(reach.shape[0]):
                    if d < reach[r]:
                        near[i, r] += 1


@njit(cache=True)
def slab_area(poly, y0, y1, work_a, work_b):
    """Area of the polygon (vertex rows, either orientation, simple) inside y0 <= y <= y1:
    Sutherland-Hodgman against the two lines, then the shoelace formula. work_a, work_b:
    scratch of at least 2 n + 4 rows."""
    n = poly.shape[0]
    for m in range(n):
        work_a[m, 0], work_a[m, 1] = poly[m, 0], poly[m, 1]
    # Clip against y >= y0 (side +1) then y <= y1 (side -1)
    for side in (1.0, -1.0):
        yc = y0 if side > 0 else y1
        k = 0
        for m in range(n):
            px, py = work_a[m, 0], work_a[m, 1]
            qx, qy = work_a[(m + 1) % n, 0], work_a[(m + 1) % n, 1]
            pin, qin = side * (py - yc) >= 0.0, side * (qy - yc) >= 0.0
            if pin:
                work_b[k, 0], work_b[k, 1] = px, py
                k += 1
            if pin != qin:
                t = (yc - py) / (qy - py)
                work_b[k, 0], work_b[k, 1] = px + t * (qx - px), yc
                k += 1
        n = k
        for m in range(n):
            work_a[m, 0], work_a[m, 1] = work_b[m, 0], work_b[m, 1]
        if n == 0:
            return 0.0
    area = 0.0
    for m in range(n):
        m1 = (m + 1) % n
        area += work_a[m, 0] * work_a[m1, 1] - work_a[m1, 0] * work_a[m, 1]
    return abs(0.5 * area)


@njit(cache=True)
def slab_areas(polys, y0, y1, out):
    """out[i] = area of polygon polys[i] inside y0 <= y <= y1."""
    nv = polys.shape[1]
    wa = np.empty((2 * nv + 4, 2))
    wb = np.empty((2 * nv + 4, 2))
    for i in range(polys.shape[0]):
        out[i] = slab_area(polys[i], y0, y1, wa, wb)
