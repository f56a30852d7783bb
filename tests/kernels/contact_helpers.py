"""Geometry helpers shared by the contact-kernel tests (quads, brute-force overlap polygons)."""

import numpy as np

SQ = np.array([[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]])


# ---- helpers ----


def rot(a):
    return np.array([[np.cos(a), -np.sin(a)], [np.sin(a), np.cos(a)]])


def random_quad(rng, scale=1.0, spread=1.0):
    """A random convex CCW quad: a perturbed square, rotated and shifted."""
    while True:
        s = scale * rng.uniform(0.5, 1.5)
        q = (SQ - 0.5) * s + rng.uniform(-0.2, 0.2, (4, 2)) * s
        q = q @ rot(rng.uniform(0, 2 * np.pi)).T + rng.uniform(-spread, spread, 2)
        e = np.roll(q, -1, 0) - q
        if np.all(e[:, 0] * np.roll(e[:, 1], -1) - e[:, 1] * np.roll(e[:, 0], -1) > 1e-3):
            return q


def inside(p, q):
    e = np.roll(q, -1, 0) - q
    return np.all(e[:, 0] * (p[1] - q[:, 1]) - e[:, 1] * (p[0] - q[:, 0]) >= 0)


def ref_polygon(p, q):
    """Brute overlap polygon of convex CCW polygons: inner vertices + edge crossings, sorted
    by angle (CCW)."""
    pts = [v for v in p if inside(v, q)] + [v for v in q if inside(v, p)]
    n, m = len(p), len(q)
    for i in range(n):
        a, b = p[i], p[(i + 1) % n]
        for j in range(m):
            c, d = q[j], q[(j + 1) % m]
            den = (b[0] - a[0]) * (d[1] - c[1]) - (b[1] - a[1]) * (d[0] - c[0])
            if den == 0:
                continue
            t = ((c[0] - a[0]) * (d[1] - c[1]) - (c[1] - a[1]) * (d[0] - c[0])) / den
            u = ((c[0] - a[0]) * (b[1] - a[1]) - (c[1] - a[1]) * (b[0] - a[0])) / den
            if 0 <= t <= 1 and 0 <= u <= 1:
                pts.append(a + t * (b - a))
    if len(pts) < 3:
        return np.zeros((0, 2))
    pts = np.array(pts)
    m = pts.mean(0)
    return pts[np.argsort(np.arctan2(pts[:, 1] - m[1], pts[:, 0] - m[0]))]


def shoelace(pts):
    """Area and centroid of the CCW polygon pts (k, 2)."""
    x, y = pts[:, 0], pts[:, 1]
    cr = x * np.roll(y, -1) - np.roll(x, -1) * y
    area = 0.5 * cr.sum()
    if area <= 0:
        return 0.0, np.zeros(2)
    cx = ((x + np.roll(x, -1)) * cr).sum() / (6 * area)
    cy = ((y + np.roll(y, -1)) * cr).sum() / (6 * area)
    return area, np.array([cx, cy])
