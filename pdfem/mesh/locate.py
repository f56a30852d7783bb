"""Points located in a mesh of 4-node quads: the element that holds each point and the
point's natural coordinates there (the inverse of the bilinear map)."""

import numpy as np

# Corner signs of the reference square [-1, 1]^2, local nodes 0..3 counter-clockwise
XI = np.array([-1.0, 1.0, 1.0, -1.0])
ETA = np.array([-1.0, -1.0, 1.0, 1.0])
# Natural coordinates are accepted this far outside [-1, 1] (rounding on shared edges)
_TOL = 1e-9


def shape(xi, eta):
    """Bilinear shape functions at natural points: (..., 4) for xi, eta of shape (...)."""
    xi, eta = np.asarray(xi)[..., None], np.asarray(eta)[..., None]
    return 0.25 * (1.0 + XI * xi) * (1.0 + ETA * eta)


def _inverse(p, q):
    """Natural coordinates (xi, eta) of points q (m, 2) in every quad p (ne, 4, 2): Newton
    from the centre, (m, ne) each."""
    xi = np.zeros((q.shape[0], p.shape[0]))
    eta = np.zeros_like(xi)
    for _ in range(30):
        n = shape(xi, eta)
        # Residual x(xi, eta) - q and the Jacobian of the bilinear map
        r = np.einsum("mek,ekd->med", n, p) - q[:, None, :]
        dxi = 0.25 * XI * (1.0 + ETA * eta[..., None])
        deta = 0.25 * ETA * (1.0 + XI * xi[..., None])
        jx = np.einsum("mek,ekd->med", dxi, p)
        je = np.einsum("mek,ekd->med", deta, p)
        det = jx[..., 0] * je[..., 1] - jx[..., 1] * je[..., 0]
        # Solve J [dxi, deta] = -r
        du = -(je[..., 1] * r[..., 0] - je[..., 0] * r[..., 1]) / det
        dv = -(-jx[..., 1] * r[..., 0] + jx[..., 0] * r[..., 1]) / det
        xi, eta = xi + du, eta + dv
        if max(np.abs(du).max(), np.abs(dv).max()) < 1e-15:
            break
    return xi, eta


def locate(xy, conn, points):
    """For each point (m, 2): the first element of (xy, conn) holding it, and its natural
    coordinates there. Returns (elem (m,) int64, xi (m,), eta (m,)); raises ValueError for a
    point outside the mesh."""
    points = np.asarray(points, np.float64)
    p = np.asarray(xy, np.float64)[conn]
    with np.errstate(all="ignore"):
        xi, eta = _inverse(p, points)
        # Inside, and Newton converged there (the map of the found point is the point)
        r = np.einsum("mek,ekd->med", shape(xi, eta), p) - points[:, None, :]
        size = np.ptp(p.reshape(-1, 2), axis=0).max()
        inside = ((np.abs(xi) <= 1.0 + _TOL) & (np.abs(eta) <= 1.0 + _TOL)
                  & (np.hypot(r[..., 0], r[..., 1]) <= 1e-12 * size))
    if not inside.any(axis=1).all():
        raise ValueError("a point lies outside the mesh")
    elem = np.argmax(inside, axis=1)
    rows = np.arange(points.shape[0])
    return elem.astype(np.int64), xi[rows, elem], eta[rows, elem]
