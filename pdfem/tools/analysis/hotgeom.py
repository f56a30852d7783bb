"""Mesh topology for the hot-spot census: element neighbours, grain boundaries, corners and
contacts, from plain arrays.

Elements are quads ``conn`` (NE, 4) listed counter-clockwise, so a body's boundary edges,
taken in their element's order, run counter-clockwise around the body (material on the
left). Nodes belong to one body: elements that share a node share a body.
"""

import numpy as np


def element_edges(conn):
    """(4 NE, 2) node pairs of every element edge, in the element's order, and their
    element (4 NE,)."""
    edges = np.stack([conn, np.roll(conn, -1, axis=1)], axis=2).reshape(-1, 2)
    return edges, np.repeat(np.arange(conn.shape[0]), 4)


def boundary_edges(conn):
    """Boundary edges (B, 2) (those of one element only) and their element (B,)."""
    edges, owner = element_edges(conn)
    key = np.sort(edges, axis=1)
    _, inv, cnt = np.unique(key, axis=0, return_inverse=True, return_counts=True)
    once = cnt[inv.ravel()] == 1
    return edges[once], owner[once]


def node_pairs(conn, elems):
    """Unique pairs (P, 2), i < j, of the elements ``elems`` that share at least one node."""
    sub = conn[elems]
    nodes = sub.ravel()
    owner = np.repeat(elems, 4)
    order = np.argsort(nodes, kind="stable")
    nodes, owner = nodes[order], owner[order]
    pairs = []
    # Elements around one node are consecutive after the sort: pair each with the next d
    for d in range(1, len(nodes)):
        same = nodes[d:] == nodes[:-d]
        if not same.any():
            break
        pairs.append(np.stack([owner[:-d][same], owner[d:][same]], axis=1))
    if not pairs:
        return np.zeros((0, 2), np.int64)
    p = np.sort(np.concatenate(pairs), axis=1)
    return np.unique(p[p[:, 0] != p[:, 1]], axis=0)


def turning_angles(x, bedges):
    """Turning angle [rad] at the end node of each boundary edge (B,): the signed angle from
    this edge's direction to the next boundary edge's; positive at a convex corner, zero on a
    straight boundary, negative at a re-entrant one. NaN where no edge continues the
    boundary."""
    nxt = np.full(int(bedges.max()) + 1 if bedges.size else 0, -1)
    nxt[bedges[:, 0]] = np.arange(len(bedges))
    k = nxt[bedges[:, 1]]
    d_in = x[bedges[:, 1]] - x[bedges[:, 0]]
    nb = bedges[np.maximum(k, 0)]
    d_out = x[nb[:, 1]] - x[nb[:, 0]]
    cross = d_in[:, 0] * d_out[:, 1] - d_in[:, 1] * d_out[:, 0]
    ang = np.arctan2(cross, np.sum(d_in * d_out, axis=1))
    return np.where(k >= 0, ang, np.nan)


def corner_elements(x, bedges, bowner, ne, min_turn):
    """(NE,) bool: the element holds a corner node, a boundary node where the boundary turns
    by at least ``min_turn`` radians towards the material (a convex corner of interior angle
    at most pi - min_turn)."""
    ang = turning_angles(x, bedges)
    corner_nodes = bedges[ang >= min_turn, 1]
    out = np.zeros(ne, bool)
    # Both boundary edges meeting at a corner node belong to elements holding it
    at = np.isin(bedges[:, 0], corner_nodes) | np.isin(bedges[:, 1], corner_nodes)
    out[bowner[at]] = True
    return out


def segment_distance(a0, a1, b0, b1):
    """Distances (P,) between the 2-D segments a0-a1 and b0-b1 (each (P, 2)); 0 where they
    cross or overlap."""
    def point_seg(p, s0, s1):
        d = s1 - s0
        ll = np.sum(d * d, axis=1)
        t = np.clip(np.sum((p - s0) * d, axis=1) / np.where(ll > 0, ll, 1.0), 0.0, 1.0)
        return np.hypot(*(p - s0 - t[:, None] * d).T)

    def orient(p, q, r):
        return np.sign((q[:, 0] - p[:, 0]) * (r[:, 1] - p[:, 1])
                       - (q[:, 1] - p[:, 1]) * (r[:, 0] - p[:, 0]))

    dist = np.minimum.reduce([point_seg(a0, b0, b1), point_seg(a1, b0, b1),
                              point_seg(b0, a0, a1), point_seg(b1, a0, a1)])
    # A proper crossing: each segment's ends on opposite sides of the other
    cross = (orient(a0, a1, b0) * orient(a0, a1, b1) < 0) & \
        (orient(b0, b1, a0) * orient(b0, b1, a1) < 0)
    return np.where(cross, 0.0, dist)


def near_segments(x, qedges, edges, tol):
    """Pairs (i, j) of query segments ``qedges[i]`` and segments ``edges[j]`` (node pairs
    into ``x``) no farther apart than ``tol``; found through a grid of cells one longest
    segment plus ``tol`` wide, so only neighbouring cells are compared."""
    if len(qedges) == 0 or len(edges) == 0:
        return np.zeros(0, np.int64), np.zeros(0, np.int64)
    mq = 0.5 * (x[qedges[:, 0]] + x[qedges[:, 1]])
    me = 0.5 * (x[edges[:, 0]] + x[edges[:, 1]])
    length = max(np.hypot(*(x[qedges[:, 1]] - x[qedges[:, 0]]).T).max(),
                 np.hypot(*(x[edges[:, 1]] - x[edges[:, 0]]).T).max())
    cell = length + tol if length + tol > 0 else 1.0
    lo = np.minimum(mq.min(axis=0), me.min(axis=0))
    cq = np.floor((mq - lo) / cell).astype(np.int64)
    ce = np.floor((me - lo) / cell).astype(np.int64)
    ny = int(max(cq[:, 1].max(), ce[:, 1].max())) + 3
    # Cell keys of the segments, sorted, so a cell's segments are one slice
    ke = (ce[:, 0] + 1) * ny + ce[:, 1] + 1
    order = np.argsort(ke, kind="stable")
    ks = ke[order]
    qi, ej = [], []
    for dx in (-1, 0, 1):
        for dy in (-1, 0, 1):
            kq = (cq[:, 0] + 1 + dx) * ny + cq[:, 1] + 1 + dy
            a, b = np.searchsorted(ks, kq, "left"), np.searchsorted(ks, kq, "right")
            n = b - a
            qi.append(np.repeat(np.arange(len(qedges)), n))
            ej.append(order[np.repeat(a, n) + _ramps(n)])
    qi, ej = np.concatenate(qi), np.concatenate(ej)
    d = segment_distance(x[qedges[qi, 0]], x[qedges[qi, 1]], x[edges[ej, 0]], x[edges[ej, 1]])
    keep = d <= tol
    return qi[keep], ej[keep]


def _ramps(n):
    """0, 1, ..., n_0 - 1, 0, 1, ..., n_1 - 1, ...: offsets within consecutive slices."""
    total = int(n.sum())
    if total == 0:
        return np.zeros(0, np.int64)
    starts = np.repeat(np.cumsum(n) - n, n)
    return np.arange(total) - starts


def components(n, pairs):
    """Connected-component labels (n,) of the graph on n vertices with edges ``pairs``
    (P, 2): each vertex gets the smallest vertex index of its component."""
    lab = np.arange(n)
    if len(pairs) == 0:
        return lab
    i, j = pairs[:, 0], pairs[:, 1]
    # Take the smaller label across every edge, then jump pointers, until nothing changes
    while True:
        m = np.minimum(lab[i], lab[j])
        new = lab.copy()
        np.minimum.at(new, i, m)
        np.minimum.at(new, j, m)
        while True:
            nxt = new[new]
            if np.array_equal(nxt, new):
                break
            new = nxt
        if np.array_equal(new, lab):
            return lab
        lab = new
