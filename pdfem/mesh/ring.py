"""Ring mesh of one elliptical grain: a kite core inside one ring of boundary quads.

The kite mesh (:mod:`pdfem.mesh.ellipse`) puts a corner of a single element at each of the
6 hexagon vertices on the boundary; that element has two boundary edges meeting at a
corner near 180 degrees, and a hammer pressing the boundary flat folds it. The ring mesh
keeps the same 12 n boundary nodes (so the same polygon, area and mass) and gives every
boundary node two elements with one boundary edge each:

- every node has kite coordinates (kite i, s, t) in the unit square of kite i of the
  hexagon (the parametrisation of :mod:`pdfem.mesh.ellipse`: s = 1 or t = 1 is the
  boundary, s = 0 and t = 0 the edges shared with the neighbouring kites);
- the core is the square s, t <= rho of every kite, rho = n / (n + 1), cut into n x n quads
  (its nodes at s, t = j / (n + 1));
- the ring joins the core's outline (the "L" s = rho or t = rho) to the boundary's (s = 1 or
  t = 1), 2 n quads per kite, node for node along both.

Per grain 6 n^2 + 12 n quads (18, 48, 90, 144 at levels 1-4 against the kite mesh's 6, 24,
54, 96). Core cells and ring thickness are 1 / (n + 1) of the kite and boundary edges 1 / n.
Boundary nodes take the kite mesh's map (bilinear on the hexagon, radially onto the disc,
pinned to it); the core's nodes sit halfway between the bilinear hexagon and its radial
image (CORE_BLEND): mapped fully, the core's outline tends to a circle and its corner
cells' angles to 180 degrees (corner-Jacobian ratio 0.18 at level 4), unmapped the ring
grows thick where the hexagon is furthest inside the circle. Halfway the smallest ratio
min/max of corner Jacobians is 0.33, 0.45, 0.44, 0.42 at levels 1-4 (0.40 at 6, the kite
mesh's 0.155 to 0.030) and the longest edge over the shortest at most 2.1 (2.4 at 6).
"""

import numpy as np

from pdfem.mesh.ellipse import kite_positions

# Weight of the radial hexagon-to-disc map in the core's node positions (module docstring)
CORE_BLEND = 0.5


def ring_coordinates(level):
    """Kite coordinates and connectivity of the ring mesh of ``level`` n >= 1.

    Returns
    -------
    kite, s, t : (nn,) int64, float64, float64
        Node 0 is the centre (0, 0, 0). A node on the edge shared by two kites is listed
        once, with the kite that has it at t = 0 (s > 0).
    conn : (ne, 4) int64
        Counter-clockwise elements: per kite its n x n core cells, then its 2 n ring quads.
    boundary : (12 n,) int64
        Closed counter-clockwise loop of the boundary nodes from kite 0's vertex (s = t = 1),
        the order of :func:`pdfem.mesh.ellipse.ellipse_mesh`.
    """
    n = int(level)
    if n < 1 or n != level:
        raise ValueError(f"level must be an integer >= 1, got {level!r}")
    ids = {}
    kite, ss, tt = [], [], []

    def node(i, js, jt, den):
        """Id of the node (kite i, s = js/den, t = jt/den), one id for shared points."""
        # Canonical form: the centre; an s = 0 point is its neighbour's t = 0 point
        if js == 0 and jt == 0:
            i = 0
        elif js == 0:
            i, js, jt = (i + 1) % 6, jt, 0
        key = (i, js / den, jt / den)
        if key not in ids:
            ids[key] = len(kite)
            kite.append(i)
            ss.append(key[1])
            tt.append(key[2])
        return ids[key]

    node(0, 0, 0, 1)
    conn = []
    for i in range(6):
        # Core: cells (j, k) of the square s, t <= n / (n + 1), counter-clockwise in (s, t)
        c = [[node(i, j, k, n + 1) for k in range(n + 1)] for j in range(n + 1)]
        for j in range(n):
            for k in range(n):
                conn.append([c[j][k], c[j + 1][k], c[j + 1][k + 1], c[j][k + 1]])
        # The two L curves (core outline, boundary) walked from t = 0 up to the corner and on
        # to s = 0, 2 n + 1 nodes each, joined by 2 n quads
        inner = [c[n][k] for k in range(n + 1)] + [c[j][n] for j in range(n - 1, -1, -1)]
        outer = ([node(i, n, k, n) for k in range(n + 1)]
                 + [node(i, j, n, n) for j in range(n - 1, -1, -1)])
        for u in range(2 * n):
            conn.append([inner[u], outer[u], outer[u + 1], inner[u + 1]])
    # Boundary loop: per kite s = 1 from t = 0 to the corner, then t = 1 back (s > 0)
    loop = []
    for i in range(6):
        loop += [node(i, n, k, n) for k in range(n)] + [node(i, j, n, n) for j in range(n, 0, -1)]
    boundary = np.roll(np.array(loop, np.int64), -n)
    return (np.array(kite, np.int64), np.array(ss), np.array(tt), np.array(conn, np.int64),
            boundary)


def ring_mesh(a, b, level=1):
    """Mesh an ellipse of semi-axes ``a``, ``b`` into ``6 n^2 + 12 n`` quads (module docstring).

    Returns ``(xy, conn, boundary)`` as :func:`pdfem.mesh.ellipse.ellipse_mesh` does: node
    coordinates [m] (node 0 the centre), counter-clockwise connectivity, and the closed
    counter-clockwise boundary loop from ``(a, 0)``, on the ellipse to rounding.
    """
    if not (a > 0.0 and b > 0.0):
        raise ValueError(f"semi-axes must be positive, got a={a!r}, b={b!r}")
    kite, s, t, conn, boundary = ring_coordinates(level)
    # Boundary nodes on the circle, the core halfway between hexagon and disc
    xy = kite_positions(kite, s, t, CORE_BLEND)
    return xy * np.array([a, b], dtype=np.float64), conn, boundary
