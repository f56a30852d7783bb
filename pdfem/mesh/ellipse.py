"""Quad mesh of one elliptical grain, and rigid placement of a grain mesh.

The mesh is built on a regular hexagon (circumradius 1, vertex ``V_0`` on the +x axis) cut
into 6 kites ``(C, M_i, V_i, M_{i+1})``, where ``M_i`` is the midpoint of edge
``V_{i-1} V_i``. Each kite is subdivided ``n x n`` bilinearly (``6 n^2`` quads), the hexagon
is mapped radially onto the unit disc and the disc is scaled to semi-axes ``(a, b)``.

Known limitation: each hexagon vertex ``V_i`` is a boundary node touched by one element only.
On the smooth boundary that element's corner angle tends to 180 degrees, so its Jacobian
ratio falls like ``1/n`` (about 0.5/n corner-based, see tests/test_mesh.py).
"""

import numpy as np

# Apothem of the unit-circumradius hexagon
_APOTHEM = np.sqrt(3.0) / 2.0


def _hexagon_points():
    """Vertices ``V_i`` (angle 60 i deg) and edge midpoints ``M_i`` (between V_{i-1}, V_i)."""
    # Vertices on the unit circle, midpoints at the apothem, 30 deg before each vertex
    ang = np.deg2rad(60.0 * np.arange(6))
    v = np.stack([np.cos(ang), np.sin(ang)], axis=1)
    m = 0.5 * (np.roll(v, 1, axis=0) + v)
    return v, m


def _kite_numbering(n):
    """Global node ids ``idx[i, j, k]`` of node (s=j/n, t=k/n) of kite i, shape (6, n+1, n+1).

    Node 0 is the centre. Kite i owns its nodes with ``j >= 1`` (``n (n+1)`` of them); its
    edge ``s = 0`` (C to M_{i+1}) is edge ``t = 0`` of kite i+1 and takes those ids.
    """
    # Owned nodes: j = 1..n, k = 0..n, numbered kite by kite
    per = n * (n + 1)
    idx = np.zeros((6, n + 1, n + 1), dtype=np.int64)
    for i in range(6):
        idx[i, 1:, :] = 1 + i * per + np.arange(per).reshape(n, n + 1)
    # Shared edge s = 0 of kite i is edge t = 0 of kite i+1; the centre is node 0
    for i in range(6):
        idx[i, 0, 1:] = idx[(i + 1) % 6, 1:, 0]
    idx[:, 0, 0] = 0
    return idx


def _hex_to_disc(p):
    """Radial map of the hexagon onto the unit disc: ``p -> p / r_hex(theta(p))``."""
    # Hexagon gauge h(p) = |p| / r_hex(theta): largest projection on the 6 edge normals
    ang = np.deg2rad(30.0 + 60.0 * np.arange(6))
    normals = np.stack([np.cos(ang), np.sin(ang)], axis=1)
    gauge = np.max(p @ normals.T, axis=1) / _APOTHEM
    # p * h / |p|, with the centre fixed
    r = np.hypot(p[:, 0], p[:, 1])
    scale = np.divide(gauge, r, out=np.zeros_like(r), where=r > 0.0)
    return p * scale[:, None]


def kite_positions(kite, s, t, blend=1.0):
    """Unit-disc positions (nn, 2) of points given by kite coordinates: kite index ``kite``
    and ``(s, t)`` in its unit square (s = 1 or t = 1 the boundary, pinned to radius 1).

    The bilinear map of kite ``(C, M_i, V_i, M_{i+1})`` on the hexagon, then the radial map
    of the hexagon onto the disc; the map :func:`ellipse_mesh` and the ring mesh share.
    Points off the boundary move the fraction ``blend`` of the way from the hexagon to
    their radial image (1: onto it, as in the kite mesh).
    """
    # Bilinear positions on the hexagon; C is the origin
    v, m = _hexagon_points()
    kite = np.asarray(kite, np.int64)
    s = np.asarray(s, np.float64)[:, None]
    t = np.asarray(t, np.float64)[:, None]
    mi, vi, mj = m[kite], v[kite], m[(kite + 1) % 6]
    hexa = s * (1.0 - t) * mi + s * t * vi + (1.0 - s) * t * mj
    # Map to the unit disc; pin boundary points to radius 1 exactly (up to rounding)
    disc = _hex_to_disc(hexa)
    bnd = (s[:, 0] == 1.0) | (t[:, 0] == 1.0)
    rb = np.hypot(disc[bnd, 0], disc[bnd, 1])
    disc[bnd] /= rb[:, None]
    if blend == 1.0:
        return disc
    return np.where(bnd[:, None], disc, (1.0 - blend) * hexa + blend * disc)


def ellipse_mesh(a, b, level=1):
    """Mesh an ellipse with semi-axes ``a`` (local x) and ``b`` (local y) into ``6 level^2`` quads.

    Parameters
    ----------
    a, b : float
        Semi-axes [m], both > 0. The ellipse is centred at the origin and unrotated.
    level : int
        Subdivision level n >= 1 of each of the 6 hexagon kites (n x n quads per kite).

    Returns
    -------
    xy : (nn, 2) float64
        Node coordinates [m], ``nn = 1 + 6 n (n+1)``. Node 0 is the centre.
    conn : (ne, 4) int64
        Element connectivity, counter-clockwise (positive area), ``ne = 6 n^2``. Element
        ``i n^2 + j n + k`` is cell (j, k) of kite i; ``j == k`` are the kite diagonals.
    boundary : (12 n,) int64
        Closed loop of boundary nodes, counter-clockwise, starting at ``(a, 0)``.
        Boundary nodes lie exactly (to rounding) on the ellipse.
    """
    # Validate arguments
    n = int(level)
    if n < 1 or n != level:
        raise ValueError(f"level must be an integer >= 1, got {level!r}")
    if not (a > 0.0 and b > 0.0):
        raise ValueError(f"semi-axes must be positive, got a={a!r}, b={b!r}")
    idx = _kite_numbering(n)
    # Kite coordinates of every kite's owned nodes (j >= 1), the centre from kite 0
    kite = np.zeros(1 + 6 * n * (n + 1), np.int64)
    s = np.zeros(kite.shape[0])
    t = np.zeros(kite.shape[0])
    sj, tk = np.meshgrid(np.arange(1, n + 1) / n, np.arange(0, n + 1) / n, indexing="ij")
    for i in range(6):
        own = idx[i, 1:, :].ravel()
        kite[own], s[own], t[own] = i, sj.ravel(), tk.ravel()
    # Boundary loop: per kite, edge s=1 from M_i up to V_i, then edge t=1 back to M_{i+1}
    parts = [np.concatenate([idx[i, n, :n], idx[i, n:0:-1, n]]) for i in range(6)]
    boundary = np.roll(np.concatenate(parts), -n)
    # Positions on the disc, scaled to the ellipse
    xy = kite_positions(kite, s, t) * np.array([a, b], dtype=np.float64)
    # Elements (j, k) of each kite, counter-clockwise like the kite (C, M_i, V_i, M_{i+1})
    j, k = np.meshgrid(np.arange(n), np.arange(n), indexing="ij")
    conn = np.concatenate(
        [
            np.stack([q[j, k], q[j + 1, k], q[j + 1, k + 1], q[j, k + 1]], axis=-1).reshape(-1, 4)
            for q in idx
        ]
    )
    return xy, conn.astype(np.int64), boundary.astype(np.int64)


def place(xy, center, angle):
    """Rotate node coordinates by ``angle`` [rad, counter-clockwise], then translate to ``center``.

    Returns a new (nn, 2) float64 array; ``xy`` is not modified.
    """
    # Rotation matrix applied to row vectors, then translation
    c, s = np.cos(angle), np.sin(angle)
    rot = np.array([[c, -s], [s, c]])
    return np.asarray(xy, dtype=np.float64) @ rot.T + np.asarray(center, dtype=np.float64)
