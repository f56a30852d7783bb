"""Geometry checks at t=0: grains and blocks inside the domain box, no overlaps.

A grain is tested as the convex polygon of NPOLY points on its ellipse, inflated about its
centre by the relative INFLATE, so grains that touch count as overlapping. Two convex
polygons are disjoint iff some edge normal of either separates them (separating axis
theorem). The support of such a polygon has a closed form, so each pair costs NPOLY axes of
a few flops, vectorised over the candidate pairs; candidates are the pairs whose bounding
boxes intersect, found with a uniform grid. The search for the first overlap forms them for a
block of grains at a time and stops at the first overlap found, so a scene of many
coincident grains is refused at once rather than after forming every one of its pairs.
"""

import numpy as np

NPOLY = 64
INFLATE = 1e-9
_STEP = 2.0 * np.pi / NPOLY
# Pairs tested per vectorised chunk (bounds the temporary arrays to a few MB each)
_CHUNK = 8192
# Candidate pairs formed per block of grains by the first-overlap search
_BLOCK_PAIRS = 8 * _CHUNK


def ellipse_aabb(center, axes, angle):
    """Exact axis-aligned bounding boxes (lo, hi), each (n, 2), of rotated ellipses."""
    c, s = np.cos(angle), np.sin(angle)
    a, b = axes[:, 0], axes[:, 1]
    half = np.stack([np.hypot(a * c, b * s), np.hypot(a * s, b * c)], axis=1)
    return center - half, center + half


def first_outside(lo, hi, box):
    """Index of the first box (lo, hi) not inside ``box`` = [x0, y0, x1, y1], or -1."""
    out = ((lo[:, 0] < box[0]) | (lo[:, 1] < box[1]) | (hi[:, 0] > box[2])
           | (hi[:, 1] > box[3]))
    bad = np.nonzero(out)[0]
    return int(bad[0]) if bad.size else -1


class BoxGrid:
    """Boxes [lo, hi] entered in every cell of a uniform grid that they touch.

    Cells are of the median box extent, coarsened while that makes more than 16 entries per
    box, so a few large grains among many small ones cost little. Entry e (box order) is box
    ``box[e]`` in cell ``cell[e]``; box b's entries are ``off[b]:off[b + 1]``. The entries
    sorted by (cell, box) have keys ``key`` = compact cell index x n + box.
    """

    def __init__(self, lo, hi):
        n = lo.shape[0]
        self.n, self.lo, self.hi = n, lo, hi
        # Cell size and the cell range of every box
        size = float(np.median(np.max(hi - lo, axis=1)))
        origin = lo.min(axis=0)
        while True:
            c0 = np.floor((lo - origin) / size).astype(np.int64)
            c1 = np.floor((hi - origin) / size).astype(np.int64)
            span = c1 - c0 + 1
            k = span[:, 0] * span[:, 1]
            if k.sum() <= 16 * n:
                break
            size *= 2.0
        self.origin, self.size, self.ny = origin, size, int(c1[:, 1].max()) + 1
        # One entry per (box, cell), in box order
        self.off = np.concatenate([[0], np.cumsum(k)])
        self.box = np.repeat(np.arange(n), k)
        r = np.arange(self.box.size) - np.repeat(self.off[:-1], k)
        self.cell = (c0[self.box, 0] + r // span[self.box, 1]) * self.ny + c0[self.box, 1] \
            + r % span[self.box, 1]
        # The entries sorted by (cell, box), as keys compact cell x n + box
        self.cid = np.unique(self.cell, return_inverse=True)[1].reshape(-1)
        self.key = np.sort(self.cid * n + self.box)

    def later(self, entries):
        """(start, stop) in ``key`` of the entries of each entry's cell with a higher box."""
        c, b = self.cid[entries], self.box[entries]
        return (np.searchsorted(self.key, c * self.n + b, side="right"),
                np.searchsorted(self.key, (c + 1) * self.n, side="left"))

    def pairs(self, entries, start, stop):
        """Pairs (i, j), i < j, sorted by (i, j), of the entries with the later entries of
        their cell in [start, stop), kept when the boxes intersect (closed), and only in the
        cell holding the lower-left corner of the intersection (hence once)."""
        m = stop - start
        src = np.repeat(entries, m)
        pos = np.repeat(start, m) + np.arange(src.size) - np.repeat(np.cumsum(m) - m, m)
        i, j, c = self.box[src], self.key[pos] % self.n, self.cell[src]
        lo, hi = self.lo, self.hi
        # Intersecting boxes, counted in one cell only
        hit = np.all((lo[i] <= hi[j]) & (lo[j] <= hi[i]), axis=1)
        i, j, c = i[hit], j[hit], c[hit]
        corner = np.floor((np.maximum(lo[i], lo[j]) - self.origin) / self.size).astype(np.int64)
        once = corner[:, 0] * self.ny + corner[:, 1] == c
        i, j = i[once], j[once]
        srt = np.lexsort((j, i))
        return i[srt], j[srt]


def candidate_pairs(lo, hi):
    """Pairs (i, j), i < j, whose boxes [lo, hi] intersect (closed), sorted by (i, j).

    Formed within the cells of a :class:`BoxGrid`, each pair once.
    """
    if lo.shape[0] < 2:
        return np.zeros(0, np.int64), np.zeros(0, np.int64)
    grid = BoxGrid(lo, hi)
    entries = np.arange(grid.box.size)
    return grid.pairs(entries, *grid.later(entries))


def polygon_support(axes, angle, n):
    """Support h(n) = max over the inflated polygon of n . (p - centre); n unit, (m, k, 2).

    The polygon's vertices are (a cos t_k, b sin t_k) rotated by the angle, t_k = k 2pi/NPOLY;
    n . p = R cos(t - psi), so the maximum is R cos of the distance from psi to the nearest t_k.
    """
    c, s = np.cos(angle)[:, None], np.sin(angle)[:, None]
    nu = n[..., 0] * c + n[..., 1] * s
    nv = -n[..., 0] * s + n[..., 1] * c
    p, q = axes[:, 0:1] * nu, axes[:, 1:2] * nv
    r = np.mod(np.arctan2(q, p), _STEP)
    return np.hypot(p, q) * np.cos(np.minimum(r, _STEP - r)) * (1.0 + INFLATE)


def polygon_normals(axes, angle):
    """(m, NPOLY/2, 2) unit edge normals of each polygon (the other half are opposites)."""
    t = (np.arange(NPOLY // 2) + 0.5) * _STEP
    lx = axes[:, 1:2] * np.cos(t)
    ly = axes[:, 0:1] * np.sin(t)
    c, s = np.cos(angle)[:, None], np.sin(angle)[:, None]
    nrm = np.stack([c * lx - s * ly, s * lx + c * ly], axis=2)
    return nrm / np.linalg.norm(nrm, axis=2, keepdims=True)


def grains_overlap(center, axes, angle, i, j):
    """Boolean mask: do the polygons of grains i[k] and j[k] overlap (SAT)?"""
    out = np.zeros(i.size, bool)
    # Quick answers: beyond the circumscribed circles, within the inscribed ones
    dist = np.hypot(*(center[j] - center[i]).T)
    big = (axes[i].max(axis=1) + axes[j].max(axis=1)) * (1.0 + INFLATE)
    small = (axes[i].min(axis=1) + axes[j].min(axis=1)) * np.cos(0.5 * _STEP)
    out[dist < small] = True
    todo = np.nonzero((dist >= small) & (dist <= big))[0]
    # Separating axes for the rest
    for k0 in range(0, todo.size, _CHUNK):
        sel = todo[k0:k0 + _CHUNK]
        a, b = i[sel], j[sel]
        d = center[b] - center[a]
        ax = np.concatenate([polygon_normals(axes[a], angle[a]),
                             polygon_normals(axes[b], angle[b])], axis=1)
        gap = (np.abs(np.einsum("mkc,mc->mk", ax, d))
               - polygon_support(axes[a], angle[a], ax) - polygon_support(axes[b], angle[b], ax))
        out[sel] = ~np.any(gap > 0.0, axis=1)
    return out


def first_grain_overlap(center, axes, angle, block_pairs=_BLOCK_PAIRS):
    """The first overlapping pair (i, j), i < j, in (i, j) order, or None.

    Grains are taken in blocks of consecutive ids holding at most about ``block_pairs``
    candidate pairs (at least one grain each); a block's candidates (i, j > i) are formed,
    sorted and tested in order, and the search stops at the first overlap. A block holds every
    candidate of its grains, so the pair found is the one the search of all pairs finds first.
    """
    n = center.shape[0]
    if n < 2:
        return None
    lo, hi = ellipse_aabb(center, axes, angle)
    # Inflate the boxes like the polygons so that touching pairs are candidates
    pad = INFLATE * (hi - lo)
    grid = BoxGrid(lo - pad, hi + pad)
    # Per entry the range of its cell's later boxes; per grain a bound on its candidates
    start, stop = grid.later(np.arange(grid.box.size))
    bound = np.concatenate([[0], np.cumsum(np.bincount(grid.box, weights=stop - start,
                                                       minlength=n))])
    g0 = 0
    while g0 < n:
        g1 = max(g0 + 1, int(np.searchsorted(bound, bound[g0] + block_pairs, side="right")) - 1)
        e = np.arange(grid.off[g0], grid.off[g1])
        i, j = grid.pairs(e, start[e], stop[e])
        # Tested in (i, j) order, a chunk at a time: the first hit is the first pair
        for k0 in range(0, i.size, _CHUNK):
            hit = np.nonzero(grains_overlap(center, axes, angle, i[k0:k0 + _CHUNK],
                                            j[k0:k0 + _CHUNK]))[0]
            if hit.size:
                return int(i[k0 + hit[0]]), int(j[k0 + hit[0]])
        g0 = g1
    return None


def first_grain_block_overlap(center, axes, angle, boxes):
    """The first (grain, block) whose grain polygon overlaps the block rectangle, or None.

    Grains are scanned in order, blocks in order for each grain. Axes: x, y and the
    grain's edge normals; the rectangle's support is |nx| wx + |ny| wy.
    """
    if center.shape[0] == 0 or not boxes:
        return None
    lo, hi = ellipse_aabb(center, axes, angle)
    pad = INFLATE * (hi - lo)
    lo, hi = lo - pad, hi + pad
    found = []
    for bi, (x0, y0, x1, y1) in enumerate(boxes):
        g = np.nonzero((lo[:, 0] <= x1) & (hi[:, 0] >= x0) & (lo[:, 1] <= y1)
                       & (hi[:, 1] >= y0))[0]
        if g.size == 0:
            continue
        ax = np.concatenate([np.broadcast_to([[[1.0, 0.0], [0.0, 1.0]]], (g.size, 2, 2)),
                             polygon_normals(axes[g], angle[g])], axis=1)
        d = np.array([0.5 * (x0 + x1), 0.5 * (y0 + y1)]) - center[g]
        rect = np.abs(ax[..., 0]) * 0.5 * (x1 - x0) + np.abs(ax[..., 1]) * 0.5 * (y1 - y0)
        gap = (np.abs(np.einsum("mkc,mc->mk", ax, d)) - polygon_support(axes[g], angle[g], ax)
               - rect)
        hit = g[~np.any(gap > 0.0, axis=1)]
        if hit.size:
            found.append((int(hit[0]), bi))
    return min(found) if found else None


def first_block_overlap(boxes):
    """The first pair (i, j) of rectangles whose interiors intersect, or None (touching is fine)."""
    for i, (a0, b0, a1, b1) in enumerate(boxes):
        for j in range(i + 1, len(boxes)):
            c0, d0, c1, d1 = boxes[j]
            if max(a0, c0) < min(a1, c1) and max(b0, d0) < min(b1, d1):
                return i, j
    return None
