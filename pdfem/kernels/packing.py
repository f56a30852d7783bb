"""Hard convex polygons in a box: contact scales, Monte Carlo moves, gaps, slab areas.

A grain is the convex polygon of its mesh's boundary nodes, given by its centre c and its
vertex offsets v (counter-clockwise, at full size). Scaled by s about its centre it covers
c + s K. Two such polygons overlap at scale s exactly when (c_j - c_i)/s lies in the
Minkowski difference M = K_i + (-K_j), a convex polygon holding the origin, so the scale at
which they first touch is the gauge of M at d = c_j - c_i:

    s_ij = max over the edge normals n of M of (n . d) / h_M(n),   h_M(n) = h_i(n) + h_j(-n),

with h the support functions and the normals of M those of K_i and of -K_j (the normals need
no normalising: each term is homogeneous in n). The polygons are disjoint for s < s_ij. With a
scale of its own for each grain, c_i + s_i K_i and c_j + s_j K_j are disjoint iff some such n
has n . d > s_i h_i(n) + s_j h_j(-n); the largest s_i that allows (the other at s_j) is
max over n of (n . d - s_j h_j(-n)) / h_i(n). A wall x = x0 (and the others) allows
s <= (c_x - x0) / h(-e_x). Everything here is exact arithmetic on the vertices (no
tolerance), so the packing never overlaps its own test.

Neighbours come from a cell list (pdfem.kernels.cell_list): a grain's are in the 3 x 3 cells
around its (possibly stale) cell; the caller keeps the cell side h >= 2 R_max + 2 * (the
largest move since the last rebuild), R the circumradius.
"""

import math

import numpy as np
from numba import njit

from pdfem.kernels.cell_list import around
from pdfem.kernels.polygon import slab_area


@njit(cache=True)
def _reach(v, nx, ny):
    """max over the vertices v of -(n . v): the support of -K in the direction n."""
    h = -math.inf
    for m in range(v.shape[0]):
        h = max(h, -(nx * v[m, 0] + ny * v[m, 1]))
    return h


@njit(cache=True)
def pair_limit(cxi, cyi, vi, cxj, cyj, vj, sj):
    """Largest scale of polygon i (strictly below it) at which c_i + s K_i stays disjoint from
    c_j + sj K_j: the polygons are disjoint iff some normal n of M = K_i + (-K_j) has
    n . d > s h_i(n) + sj h_j(-n), so the limit is max over n of (n . d - sj h_j(-n)) / h_i(n)
    (see the module docstring)."""
    dx, dy = cxj - cxi, cyj - cyi
    ni, nj = vi.shape[0], vj.shape[0]
    g = -math.inf
    # Edge normals n of K_i (h_i(n) the edge's offset), then -m for the normals m of K_j
    for k in range(ni):
        k1 = k + 1 if k + 1 < ni else 0
        nx, ny = vi[k1, 1] - vi[k, 1], vi[k, 0] - vi[k1, 0]
        g = max(g, (nx * dx + ny * dy - sj * _reach(vj, nx, ny))
                / (nx * vi[k, 0] + ny * vi[k, 1]))
    for k in range(nj):
        k1 = k + 1 if k + 1 < nj else 0
        mx, my = vj[k1, 1] - vj[k, 1], vj[k, 0] - vj[k1, 0]
        g = max(g, (-(mx * dx + my * dy) - sj * (mx * vj[k, 0] + my * vj[k, 1]))
                / _reach(vi, mx, my))
    return g


@njit(cache=True)
def pair_scale(cxi, cyi, vi, cxj, cyj, vj):
    """Common scale s_ij at which c_i + s K_i and c_j + s K_j first touch: the gauge of M at
    d = c_j - c_i (see the module docstring); disjoint for s < s_ij."""
    dx, dy = cxj - cxi, cyj - cyi
    ni, nj = vi.shape[0], vj.shape[0]
    g = 0.0
    for k in range(ni):
        k1 = k + 1 if k + 1 < ni else 0
        nx, ny = vi[k1, 1] - vi[k, 1], vi[k, 0] - vi[k1, 0]
        g = max(g, (nx * dx + ny * dy) / (nx * vi[k, 0] + ny * vi[k, 1] + _reach(vj, nx, ny)))
    for k in range(nj):
        k1 = k + 1 if k + 1 < nj else 0
        mx, my = vj[k1, 1] - vj[k, 1], vj[k, 0] - vj[k1, 0]
        g = max(g, -(mx * dx + my * dy) / (_reach(vi, mx, my) + mx * vj[k, 0] + my * vj[k, 1]))
    return g


@njit(cache=True)
def wall_scale(cx, cy, v, x0, y0, x1, y1):
    """Largest scale at which c + s K stays inside the box [x0, x1] x [y0, y1]."""
    left = right = down = up = 0.0
    for m in range(v.shape[0]):
        left = max(left, -v[m, 0])
        right = max(right, v[m, 0])
        down = max(down, -v[m, 1])
        up = max(up, v[m, 1])
    return min((cx - x0) / left, (x1 - cx) / right, (cy - y0) / down, (y1 - cy) / up)


@njit(cache=True)
def rotate_into(base, angle, out):
    """out = base rotated counter-clockwise by angle (rows are points)."""
    c, s = math.cos(angle), math.sin(angle)
    for m in range(base.shape[0]):
        out[m, 0] = c * base[m, 0] - s * base[m, 1]
        out[m, 1] = s * base[m, 0] + c * base[m, 1]


@njit(cache=True)
def _limit_at(i, cxi, cyi, vi, cx, cy, verts, rad, scale, s_stop, box, cell, start, items,
              nx, ny):
    """Largest scale of grain i placed at (cxi, cyi) with vertices vi against the walls and
    its neighbours j at their scales (the cells around cell[i]); returns early once the
    value is <= s_stop."""
    best = wall_scale(cxi, cyi, vi, box[0], box[1], box[2], box[3])
    if best <= s_stop:
        return best
    cells = np.empty(9, np.int64)
    for m in range(around(cell[i], nx, ny, cells)):
        k = cells[m]
        for q in range(start[k], start[k + 1]):
            j = items[q]
            if j == i:
                continue
            # Circumscribed circles: the limit is at least (|d| - s_j R_j) / R_i
            d = math.hypot(cx[j] - cxi, cy[j] - cyi)
            if d - scale[j] * rad[j] >= best * rad[i]:
                continue
            lim = pair_limit(cxi, cyi, vi, cx[j], cy[j], verts[j], scale[j])
            if lim < best:
                best = lim
                if best <= s_stop:
                    return best
    return best


@njit(cache=True)
def grow_sweep(cx, cy, verts, rad, scale, rate, box, cell, start, items, nx, ny):
    """Every grain in index order grows half-way to the largest scale its walls and
    neighbours (at their current scales) allow, by the factor 1 + rate at most, to 1 at most
    (a grain that took all its room at once would leave the moves none). Returns the
    smallest scale."""
    smin = math.inf
    for i in range(cx.shape[0]):
        if scale[i] < 1.0:
            lim = _limit_at(i, cx[i], cy[i], verts[i], cx, cy, verts, rad, scale, -math.inf,
                            box, cell, start, items, nx, ny)
            new = min(scale[i] + 0.5 * (lim - scale[i]), scale[i] * (1.0 + rate))
            scale[i] = 1.0 if new >= 1.0 and lim > 1.0 else min(new, 1.0)
        smin = min(smin, scale[i])
    return smin


@njit(cache=True)
def min_pair_scale(cx, cy, verts, rad, box, cell, start, items, nx, ny):
    """Smallest common scale at which some grain touches a wall or a neighbour (> 1: the
    grains are disjoint at full size)."""
    best = math.inf
    cells = np.empty(9, np.int64)
    for i in range(cx.shape[0]):
        best = min(best, wall_scale(cx[i], cy[i], verts[i], box[0], box[1], box[2], box[3]))
        for m in range(around(cell[i], nx, ny, cells)):
            k = cells[m]
            for q in range(start[k], start[k + 1]):
                j = items[q]
                if j <= i or math.hypot(cx[j] - cx[i], cy[j] - cy[i]) >= \
                        best * (rad[i] + rad[j]):
                    continue
                best = min(best, pair_scale(cx[i], cy[i], verts[i], cx[j], cy[j], verts[j]))
    return best


@njit(cache=True)
def _slice_delta(v, cx, cy, sign, edges, delta, poly, wa, wb, lo_hi):
    """Add sign x (area of polygon c + v in slice k) to delta[k] for the slices it spans;
    lo_hi receives the first and last slice index touched; poly, wa, wb: scratch."""
    nsl = edges.shape[0] - 1
    thick = (edges[nsl] - edges[0]) / nsl
    ylo, yhi = math.inf, -math.inf
    for m in range(v.shape[0]):
        ylo = min(ylo, cy + v[m, 1])
        yhi = max(yhi, cy + v[m, 1])
    k0 = min(max(int((ylo - edges[0]) / thick), 0), nsl - 1)
    k1 = min(max(int((yhi - edges[0]) / thick), 0), nsl - 1)
    for m in range(v.shape[0]):
        poly[m, 0], poly[m, 1] = cx + v[m, 0], cy + v[m, 1]
    for k in range(k0, k1 + 1):
        delta[k] += sign * slab_area(poly, edges[k], edges[k + 1], wa, wb)
    lo_hi[0], lo_hi[1] = min(lo_hi[0], k0), max(lo_hi[1], k1)


@njit(cache=True)
def mc_sweep(cx, cy, angle, verts, base, rad, scale, rnd, delta, box, cell, start, items, nx,
             ny, trial, edges, slab, target, beta):
    """One Monte Carlo sweep of hard polygons at their scales: grain i in index order tries the
    move (dx, dy, dtheta) = (2 rnd[i, :3] - 1) * (delta, delta, delta / rad[i]) and keeps it
    when the moved grain overlaps no wall and no neighbour. Returns the number of accepted
    moves.

    With beta > 0 (every scale 1) the arrangement also carries the energy
    E = beta sum_k (slab[k] - target)^2 of the grain area slab[k] in the slices between
    ``edges``: a move allowed by the hard cores is kept with the Metropolis probability
    min(1, exp(-dE)) (rnd[i, 3] decides), and slab is kept up to date."""
    acc = 0
    nsl = edges.shape[0] - 1
    dsl = np.zeros(max(nsl, 1))
    nv = base.shape[1]
    poly = np.empty((nv, 2))
    wa = np.empty((2 * nv + 4, 2))
    wb = np.empty((2 * nv + 4, 2))
    span = np.empty(2, np.int64)
    for i in range(cx.shape[0]):
        tx = cx[i] + (2.0 * rnd[i, 0] - 1.0) * delta
        ty = cy[i] + (2.0 * rnd[i, 1] - 1.0) * delta
        ta = angle[i] + (2.0 * rnd[i, 2] - 1.0) * delta / rad[i]
        rotate_into(base[i], ta, trial)
        if _limit_at(i, tx, ty, trial, cx, cy, verts, rad, scale, scale[i], box, cell, start,
                     items, nx, ny) <= scale[i]:
            continue
        if beta > 0.0:
            # Change of the slice areas, and of the energy, if the grain moved
            span[0], span[1] = nsl, -1
            _slice_delta(verts[i], cx[i], cy[i], -1.0, edges, dsl, poly, wa, wb, span)
            _slice_delta(trial, tx, ty, 1.0, edges, dsl, poly, wa, wb, span)
            de = 0.0
            for k in range(span[0], span[1] + 1):
                de += beta * ((slab[k] + dsl[k] - target) ** 2 - (slab[k] - target) ** 2)
            keep = de <= 0.0 or rnd[i, 3] < math.exp(-de)
            for k in range(span[0], span[1] + 1):
                if keep:
                    slab[k] += dsl[k]
                dsl[k] = 0.0
            if not keep:
                continue
        cx[i], cy[i], angle[i] = tx, ty, ta
        verts[i, :, :] = trial
        acc += 1
    return acc


@njit(cache=True)
def rsa_place(cx, cy, angle, verts, base, rad, rnd, lo, hi, s, box, h, nx, ny, head, nxt, first,
              trial):
    """Random sequential addition at scale s: grain i = first + r, r < rnd.shape[0], tries the
    positions (x0 + rnd[r, t, 0] (x1 - x0), lo[i] + rnd[r, t, 1] (hi[i] - lo[i])),
    t = 0, 1, ..., and takes the first where it overlaps no wall and no grain placed before
    it. The cell grid is a linked list (head per cell, nxt per grain) of the placed grains.
    Returns the index of the first grain that found no place (first + rnd.shape[0] when all
    of them are placed)."""
    for i in range(first, first + rnd.shape[0]):
        r = i - first
        rotate_into(base[i], angle[i], trial)
        placed = False
        for t in range(rnd.shape[1]):
            tx = box[0] + rnd[r, t, 0] * (box[2] - box[0])
            ty = lo[i] + rnd[r, t, 1] * (hi[i] - lo[i])
            if wall_scale(tx, ty, trial, box[0], box[1], box[2], box[3]) <= s:
                continue
            ix = min(max(int((tx - box[0]) / h), 0), nx - 1)
            iy = min(max(int((ty - box[1]) / h), 0), ny - 1)
            ok = True
            for ax in range(max(ix - 1, 0), min(ix + 2, nx)):
                for ay in range(max(iy - 1, 0), min(iy + 2, ny)):
                    j = head[ax * ny + ay]
                    while j >= 0 and ok:
                        d = math.hypot(cx[j] - tx, cy[j] - ty)
                        if d < s * (rad[i] + rad[j]) and \
                                pair_scale(tx, ty, trial, cx[j], cy[j], verts[j]) <= s:
                            ok = False
                        j = nxt[j]
            if ok:
                cx[i], cy[i] = tx, ty
                verts[i, :, :] = trial
                k = ix * ny + iy
                nxt[i] = head[k]
                head[k] = i
                placed = True
                break
        if not placed:
            return i
    return first + rnd.shape[0]
