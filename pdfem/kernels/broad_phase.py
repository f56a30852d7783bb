"""Broad phase of contact detection: element bounding boxes and candidate element pairs.

The cell grid (:mod:`pdfem.kernels.neighbours`) gives candidate grain pairs at each rebuild;
every step the kernels here reduce them to the boundary-element pairs (and element-wall pairs)
whose boxes lie within the skin, which :mod:`pdfem.kernels.overlap` then clips.
"""

import numpy as np
from numba import njit


@njit(cache=True)
def element_corners(x, conn, e, xe):
    """Current coordinates of element e's four nodes into xe (4, 2)."""
    for k in range(4):
        xe[k, 0] = x[conn[e, k], 0]
        xe[k, 1] = x[conn[e, k], 1]


@njit(cache=True)
def element_bboxes(x, conn, e0, e1, out):
    """out[e] = (xmin, ymin, xmax, ymax) of element e's nodes for e in [e0, e1)."""
    for e in range(e0, e1):
        n0 = conn[e, 0]
        out[e, 0] = x[n0, 0]
        out[e, 1] = x[n0, 1]
        out[e, 2] = x[n0, 0]
        out[e, 3] = x[n0, 1]
        for k in range(1, conn.shape[1]):
            nk = conn[e, k]
            out[e, 0] = min(out[e, 0], x[nk, 0])
            out[e, 1] = min(out[e, 1], x[nk, 1])
            out[e, 2] = max(out[e, 2], x[nk, 0])
            out[e, 3] = max(out[e, 3], x[nk, 1])


@njit(cache=True)
def boxes_near(bi, bj, skin):
    """True when boxes bi, bj (xmin, ymin, xmax, ymax) are at most skin apart in x and in y."""
    return (
        bi[0] - bj[2] <= skin
        and bj[0] - bi[2] <= skin
        and bi[1] - bj[3] <= skin
        and bj[1] - bi[3] <= skin
    )


@njit(cache=True)
def _on_boundary(ebnd, e):
    """True when element e has at least one grain-boundary edge."""
    for k in range(ebnd.shape[1]):
        if ebnd[e, k] != 0:
            return True
    return False


@njit(cache=True)
def _emit(out, n, a, b, k, egid, eloc):
    """Store pair n as (lower global key, higher global key) if it fits, with b's period shift
    k in a third column where out has one (negated when the pair is turned); return n + 1."""
    if egid[a] > egid[b] or (egid[a] == egid[b] and eloc[a] > eloc[b]):
        a, b, k = b, a, -k
    if n < out.shape[0]:
        out[n, 0] = a
        out[n, 1] = b
        if out.shape[1] > 2:
            out[n, 2] = k
    return n + 1


@njit(cache=True)
def pairs_from_bboxes(bbox, ebnd, egid, eloc, e0, e1, skin, out):
    """Brute force reference: all pairs of boundary elements in [e0, e1) of different bodies
    whose bboxes are within skin (boxes_near), oriented lower global key first, into out (cap, 2).

    Returns the number of pairs found; only the first cap are written (call again if larger).
    """
    n = 0
    for i in range(e0, e1):
        if not _on_boundary(ebnd, i):
            continue
        for j in range(i + 1, e1):
            if egid[j] != egid[i] and _on_boundary(ebnd, j) and boxes_near(bbox[i], bbox[j], skin):
                n = _emit(out, n, i, j, 0, egid, eloc)
    return n


@njit(cache=True)
def _rows_near(a, i, b, j, skin, sh):
    """boxes_near of rows a[i] and b[j] (b's shifted by sh in x), indexed in place (no row views
    in the hot loops)."""
    return (a[i, 0] - (b[j, 2] + sh) <= skin and (b[j, 0] + sh) - a[i, 2] <= skin
            and a[i, 1] - b[j, 3] <= skin and b[j, 1] - a[i, 3] <= skin)


@njit(cache=True)
def _near_list(bbox, ebnd, e0, e1, boxes, b, sh, skin, deep, lst):
    """Boundary elements (with deep, all elements) of [e0, e1) within skin of boxes[b] shifted
    by sh in x, into lst; return their count."""
    c = 0
    for e in range(e0, e1):
        if (deep or _on_boundary(ebnd, e)) and _rows_near(bbox, e, boxes, b, skin, sh):
            lst[c] = e
            c += 1
    return c


@njit(cache=True)
def _body_box(bbox, ebnd, e0, e1, deep, box):
    """Union of the bboxes of the boundary elements (with deep, all elements) of [e0, e1) into
    box."""
    box[0] = np.inf
    box[1] = np.inf
    box[2] = -np.inf
    box[3] = -np.inf
    for e in range(e0, e1):
        if deep or _on_boundary(ebnd, e):
            box[0] = min(box[0], bbox[e, 0])
            box[1] = min(box[1], bbox[e, 1])
            box[2] = max(box[2], bbox[e, 2])
            box[3] = max(box[3], bbox[e, 3])


@njit(cache=True)
def candidate_pairs(bbox, ebnd, egid, eloc, body_e0, body_e1, bpairs, skin, deep, period, out):
    """Boundary-element pairs of the candidate body pairs bpairs (nb, 2) whose bboxes are within
    skin (boxes_near); with deep, the pairs of a boundary element of either body and any
    element of the other. Body i owns elements [body_e0[i], body_e1[i]). Pairs come out in
    body-pair order, then element order, oriented lower global key first, into out (cap, 2);
    returns the number found (only the first cap are written). Without deep, the same set as
    pairs_from_bboxes. Periodic sides: a third column of bpairs (nb, 3) holds the shift k of
    the pair's second body, met k periods (period [m]) to the right, and out (cap, 3) gets each
    pair's shift (negated where the pair is turned to put the lower key first).
    """
    big = 1
    for q in range(bpairs.shape[0]):
        for s in range(2):
            big = max(big, body_e1[bpairs[q, s]] - body_e0[bpairs[q, s]])
    la = np.empty(big, dtype=np.int64)
    lb = np.empty(big, dtype=np.int64)
    # Bounding box of each body's boundary elements (empty box when it has none), once
    boxes = np.empty((body_e0.shape[0], 4))
    for i in range(body_e0.shape[0]):
        _body_box(bbox, ebnd, body_e0[i], body_e1[i], deep, boxes[i])
    shifted = bpairs.shape[1] > 2
    n = 0
    for q in range(bpairs.shape[0]):
        i = bpairs[q, 0]
        j = bpairs[q, 1]
        k = bpairs[q, 2] if shifted else 0
        if body_e1[i] <= body_e0[i] or body_e1[j] <= body_e0[j]:
            continue
        if egid[body_e0[i]] == egid[body_e0[j]]:
            continue
        if egid[body_e0[i]] > egid[body_e0[j]]:
            i, j, k = j, i, -k
        sh = k * period
        # Boundary elements of each body near the other body, then all their pairs
        na = _near_list(bbox, ebnd, body_e0[i], body_e1[i], boxes, j, sh, skin, deep, la)
        nb = _near_list(bbox, ebnd, body_e0[j], body_e1[j], boxes, i, -sh, skin, deep, lb)
        for u in range(na):
            bu = not deep or _on_boundary(ebnd, la[u])
            for v in range(nb):
                if not bu and not _on_boundary(ebnd, lb[v]):
                    continue
                if _rows_near(bbox, la[u], bbox, lb[v], skin, sh):
                    n = _emit(out, n, la[u], lb[v], k, egid, eloc)
    return n


@njit(cache=True)
def wall_crossings(bbox, ebnd, e0, e1, p0, normal, reach, out_e, out_w):
    """Boundary elements of [e0, e1) whose bbox reaches closer than ``reach`` to wall w's
    half-plane, n.(p - p0) < reach at some corner (reach 0: behind the wall), wall by wall then
    element by element, into out_e / out_w; returns the count (only the first out_e.shape[0]
    are written: call again with room for all)."""
    m = 0
    for w in range(p0.shape[0]):
        nx = normal[w, 0]
        ny = normal[w, 1]
        for e in range(e0, e1):
            if not _on_boundary(ebnd, e):
                continue
            # Lowest n.(p - p0) over the box corners
            lo = min(nx * (bbox[e, 0] - p0[w, 0]), nx * (bbox[e, 2] - p0[w, 0])) + \
                min(ny * (bbox[e, 1] - p0[w, 1]), ny * (bbox[e, 3] - p0[w, 1]))
            if lo < reach:
                if m < out_e.shape[0]:
                    out_e[m] = e
                    out_w[m] = w
                m += 1
    return m
