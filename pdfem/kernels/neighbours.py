"""First-level contact detection on the cell grid, and the packing of contact keys for sorting."""

import numpy as np
from numba import njit


@njit(cache=True)
def body_boxes(bbox, estart, ne, b0, b1, out):
    """Bounding box of the elements of each body [b0, b1) (rows xmin, ymin, xmax, ymax)."""
    for b in range(b0, b1):
        out[b, 0] = np.inf
        out[b, 1] = np.inf
        out[b, 2] = -np.inf
        out[b, 3] = -np.inf
        for e in range(estart[b], estart[b] + ne[b]):
            out[b, 0] = min(out[b, 0], bbox[e, 0])
            out[b, 1] = min(out[b, 1], bbox[e, 1])
            out[b, 2] = max(out[b, 2], bbox[e, 2])
            out[b, 3] = max(out[b, 3], bbox[e, 3])


@njit(cache=True)
def grain_pairs(cell, owned, box, nx, ny, skin, reach, period):
    """Candidate grain pairs: grains whose centroid cells are at most ``reach`` cells apart
    in x and in y (reach 1: the 3x3 block) and whose boxes are within ``skin``; at least one
    grain of each pair is owned. cell (n,) is each grain's centroid cell (-1 to ignore),
    owned (n,) a 0/1 flag, box (n, 4). With period > 0 the x sides are periodic: the columns
    wrap (each searched once, however wide the reach), and grain j is met at each of the two
    images around grain i (shifted by k periods in x) whose box is within skin of i's: both
    when the two grains span the box between them. Returns (m, 3) rows (i, j, k) of local
    indices (k = 0 without a period)."""
    n = cell.shape[0]
    ncell = nx * ny
    periodic = period > 0.0
    # Counting sort of grains by cell
    count = np.zeros(ncell + 1, np.int64)
    for i in range(n):
        if cell[i] >= 0:
            count[cell[i] + 1] += 1
    for c in range(ncell):
        count[c + 1] += count[c]
    order = np.empty(n, np.int64)
    fill = count[:-1].copy()
    for i in range(n):
        if cell[i] >= 0:
            order[fill[cell[i]]] = i
            fill[cell[i]] += 1
    # The columns around a grain's: all of them once the reach wraps past the other side
    xfrom, xto = -reach, reach
    if periodic and 2 * reach + 1 >= nx:
        xfrom, xto = 0, nx - 1
    # Owned grains against the (2 reach + 1)^2 block of cells around them
    cap = 16 * n + 16
    out = np.empty((cap, 3), np.int64)
    m = 0
    for i in range(n):
        if owned[i] == 0 or cell[i] < 0:
            continue
        cx = cell[i] % nx
        cy = cell[i] // nx
        for dy in range(-reach, reach + 1):
            for dx in range(xfrom, xto + 1):
                jx = cx + dx
                jy = cy + dy
                if periodic:
                    jx = jx % nx
                if jx < 0 or jy < 0 or jx >= nx or jy >= ny:
                    continue
                c = jx + nx * jy
                for q in range(count[c], count[c + 1]):
                    j = order[q]
                    if j == i or (owned[j] == 1 and j < i):
                        continue
                    if box[i, 1] - skin > box[j, 3] or box[j, 1] - skin > box[i, 3]:
                        continue
                    # The images of j (k periods right) around i: the one whose box starts at or
                    # left of i's and the next (no other can be within skin of a grain
                    # narrower than the box)
                    k0 = np.int64(np.floor((box[i, 0] - box[j, 0]) / period)) if periodic else 0
                    for k in range(k0, k0 + 2 if periodic else k0 + 1):
                        if not _near_x(box, i, j, k * period, skin):
                            continue
                        if m == cap:
                            grown = np.empty((2 * cap, 3), np.int64)
                            grown[:m] = out[:m]
                            out = grown
                            cap *= 2
                        out[m, 0] = i
                        out[m, 1] = j
                        out[m, 2] = k
                        m += 1
    return out[:m]


@njit(cache=True)
def _near_x(box, i, j, sh, skin):
    """Boxes i and j (j shifted by sh) within skin of each other in x."""
    return not (box[i, 0] - skin > box[j, 2] + sh or box[j, 0] + sh - skin > box[i, 2])


@njit(cache=True)
def key_spans(keys, lo, span):
    """Column minima lo (4,) and spans max - min + 1 (4,) of (n, 4) int64 keys, n >= 1."""
    for c in range(4):
        lo[c] = keys[0, c]
        span[c] = keys[0, c]
    for i in range(1, keys.shape[0]):
        for c in range(4):
            lo[c] = min(lo[c], keys[i, c])
            span[c] = max(span[c], keys[i, c])
    for c in range(4):
        span[c] = span[c] - lo[c] + 1


@njit(cache=True)
def pack_keys(keys, lo, span, out):
    """out[i] = keys[i] in mixed radix (digits keys[i, c] - lo[c], radices span[c]): an
    order-preserving int64 when the product of the spans is below 2^63 (the caller checks)."""
    for i in range(keys.shape[0]):
        v = keys[i, 0] - lo[0]
        for c in range(1, 4):
            v = v * span[c] + (keys[i, c] - lo[c])
        out[i] = v
