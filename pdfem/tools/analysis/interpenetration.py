"""Grains that have passed into each other.

A node of one grain inside another grain's boundary element is ordinary contact overlap. Past
the boundary elements, inside a grain's interior elements, it is overlap the contact law should
have stopped: under the report's area law (and any law acting between boundary elements only)
such a node feels no contact at all, the grains overlap there unopposed and the bed holds more
grain than its volume; under the potential law the grain's depth field
(pdfem.kernels.grain_depth) still pushes it back, ever harder, and a node found there marks a
contact pressed to more than a boundary element's depth. The count of such nodes is what tells
either.
"""

import numpy as np

from pdfem.tools.analysis.hotgeom import boundary_edges


def interior_elements(conn):
    """(NE,) True for the elements of ``conn`` with no edge on their grain's boundary."""
    _, owner = boundary_edges(conn)
    interior = np.ones(conn.shape[0], bool)
    interior[owner] = False
    return interior


def nodes_inside_interiors(x, conn, elem_body, node_body):
    """(NN,) True for the nodes lying inside (or on) an interior element (:func:`interior_elements`)
    of another body; ``conn`` (NE, 4) counter-clockwise quads of the grains, global node ids into
    x (NN, 2), ``elem_body`` (NE,) and ``node_body`` (NN,) their bodies. Only nodes of the bodies
    in elem_body are tested."""
    inside = np.zeros(x.shape[0], bool)
    ie = np.flatnonzero(interior_elements(conn))
    nodes = np.flatnonzero(np.isin(node_body, np.unique(elem_body)))
    if ie.size == 0 or nodes.size == 0:
        return inside
    # Nodes sorted along x: each element's candidates are a slice of its box's x range
    order = nodes[np.argsort(x[nodes, 0], kind="stable")]
    xs = x[order, 0]
    q = x[conn[ie]]
    lo, hi = q.min(axis=1), q.max(axis=1)
    first = np.searchsorted(xs, lo[:, 0], "left")
    last = np.searchsorted(xs, hi[:, 0], "right")
    for k in np.flatnonzero(last > first):
        cand = order[first[k]:last[k]]
        p = x[cand]
        keep = ((p[:, 1] >= lo[k, 1]) & (p[:, 1] <= hi[k, 1])
                & (node_body[cand] != elem_body[ie[k]]))
        if not keep.any():
            continue
        cand, p = cand[keep], p[keep]
        # Inside a counter-clockwise quad: on the left of (or on) each of its edges
        ok = np.ones(cand.size, bool)
        for i in range(4):
            a, b = q[k, i], q[k, (i + 1) % 4]
            ok &= (b[0] - a[0]) * (p[:, 1] - a[1]) - (b[1] - a[1]) * (p[:, 0] - a[0]) >= 0.0
        inside[cand[ok]] = True
    return inside
