"""Geometric quality measures and boundary extraction for 4-node quad meshes.

All functions work on any mesh given as node coordinates ``xy`` (nn, 2) and a
connectivity ``conn`` (ne, 4) with local nodes 0..3 in counter-clockwise order.
"""

import numpy as np


def areas(xy, conn):
    """Signed area [m^2] of every quad, positive for counter-clockwise nodes; shape (ne,).

    Uses half the cross product of the diagonals, exact for any (non self-crossing) quad.
    """
    # Diagonals x2 - x0 and x3 - x1
    p = np.asarray(xy, dtype=np.float64)[np.asarray(conn)]
    d1 = p[:, 2] - p[:, 0]
    d2 = p[:, 3] - p[:, 1]
    return 0.5 * (d1[:, 0] * d2[:, 1] - d1[:, 1] * d2[:, 0])


def corner_jacobians(xy, conn):
    """Jacobian determinant of the bilinear map at the 4 corners of every quad; shape (ne, 4).

    At corner k, ``det J = cross(x_{k+1} - x_k, x_{k-1} - x_k) / 4`` for the reference
    square [-1, 1]^2.
    """
    # Edge vectors leaving each corner forwards and backwards
    p = np.asarray(xy, dtype=np.float64)[np.asarray(conn)]
    fwd = np.roll(p, -1, axis=1) - p
    bwd = np.roll(p, 1, axis=1) - p
    return 0.25 * (fwd[..., 0] * bwd[..., 1] - fwd[..., 1] * bwd[..., 0])


def point_jacobians(xy, conn, points):
    """Jacobian determinant of the bilinear map of every quad at natural points
    ``[(xi, eta), ...]`` of the reference square [-1, 1]^2; shape (ne, len(points)).

    At the corners this is :func:`corner_jacobians`; at the integration points it is what an
    element kernel checks (the 1-point rule: (0, 0); 2 x 2: (+-1/sqrt3, +-1/sqrt3)).
    """
    p = np.asarray(xy, dtype=np.float64)[np.asarray(conn)]
    xi_n = np.array([-1.0, 1.0, 1.0, -1.0])
    eta_n = np.array([-1.0, -1.0, 1.0, 1.0])
    out = []
    # Derivatives of the shape functions at each point, then the 2 x 2 determinant
    for xi, eta in points:
        dxi = 0.25 * xi_n * (1.0 + eta * eta_n)
        deta = 0.25 * eta_n * (1.0 + xi * xi_n)
        xx, xy_ = p[:, :, 0] @ dxi, p[:, :, 0] @ deta
        yx, yy = p[:, :, 1] @ dxi, p[:, :, 1] @ deta
        out.append(xx * yy - xy_ * yx)
    return np.stack(out, axis=1)


def folded_area(xy, conn):
    """Area [m^2] of every quad's folded corners: the triangle (x_{k-1}, x_k, x_{k+1}) at each
    corner whose Jacobian is negative, summed; shape (ne,). Zero for a convex quad; a corner
    pushed past its neighbours' diagonal lays that much of the element over the rest of it
    (or over a neighbour), counted twice where the quad's signed area counts it once."""
    return 2.0 * np.clip(-corner_jacobians(xy, conn), 0.0, None).sum(axis=1)


def jacobian_ratio(xy, conn):
    """Ratio min/max of the corner Jacobian determinants of every quad; shape (ne,).

    1 for a parallelogram, towards 0 as a corner angle approaches 180 degrees. The divisor is
    the largest absolute determinant, so the ratio lies in [-1, 1] and is negative for a
    non-convex, inverted or clockwise quad; for valid quads it is exactly min/max.
    """
    # Smallest determinant over the largest magnitude
    det = corner_jacobians(xy, conn)
    return det.min(axis=1) / np.abs(det).max(axis=1)


def boundary_edges(conn):
    """Edges that belong to exactly one element.

    Local edge k of an element runs from its local node k to local node (k+1) % 4.

    Returns
    -------
    (nbe, 2) int64
        Rows ``(element, k)``, sorted by element then k.
    """
    # All element edges as unordered node pairs
    conn = np.asarray(conn, dtype=np.int64).reshape(-1, 4)
    if conn.shape[0] == 0:
        return np.zeros((0, 2), dtype=np.int64)
    a = conn
    b = np.roll(conn, -1, axis=1)
    pairs = np.stack([np.minimum(a, b), np.maximum(a, b)], axis=-1).reshape(-1, 2)
    # Keep the pairs seen once; row r of pairs is element r // 4, local edge r % 4
    _, inverse, counts = np.unique(pairs, axis=0, return_inverse=True, return_counts=True)
    rows = np.flatnonzero(counts[inverse.ravel()] == 1)
    return np.stack([rows // 4, rows % 4], axis=1).astype(np.int64)
