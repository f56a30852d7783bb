"""The ring grain mesh: counts, the kite mesh's boundary, one boundary edge per element, a
corner-Jacobian ratio bounded at every level, and a bed's kite meshes carried onto it."""

import numpy as np
import pytest

from pdfem.mesh.ellipse import ellipse_mesh, place
from pdfem.mesh.grain import grain_mesh, quads_per_grain
from pdfem.mesh.locate import locate, shape
from pdfem.mesh.quality import areas, boundary_edges, jacobian_ratio
from pdfem.mesh.ring import ring_mesh
from pdfem.prepare.relevel import refine_nodes, refine_points, ring_nodes, ring_points

LEVELS = [1, 2, 3, 4, 6]


@pytest.mark.parametrize("level", LEVELS)
def test_ring_counts_and_boundary(level):
    xy, conn, bnd = ring_mesh(2.0e-4, 1.0e-4, level)
    xk, _, bk = ellipse_mesh(2.0e-4, 1.0e-4, level)
    assert conn.shape == (quads_per_grain(level, "ring"), 4) == (6 * level**2 + 12 * level, 4)
    # Every node used, every element counter-clockwise, the kite mesh's boundary bit for bit
    assert np.array_equal(np.unique(conn), np.arange(xy.shape[0]))
    assert np.all(areas(xy, conn) > 0.0)
    assert np.array_equal(xy[bnd], xk[bk])
    # The same polygon: the elements tile the boundary loop's area
    p, q = xy[bnd], np.roll(xy[bnd], -1, axis=0)
    loop = 0.5 * np.sum(p[:, 0] * q[:, 1] - p[:, 1] * q[:, 0])
    assert areas(xy, conn).sum() == pytest.approx(loop, rel=1e-12)


@pytest.mark.parametrize("level", LEVELS)
def test_every_boundary_node_has_two_elements(level):
    _, conn, bnd = ring_mesh(1.0, 1.0, level)
    edges = boundary_edges(conn)
    # One boundary edge per element at most, 12 n of them, and two elements at each node
    assert np.bincount(edges[:, 0]).max() == 1 and edges.shape[0] == 12 * level
    count = np.bincount(conn.ravel(), minlength=conn.max() + 1)
    assert np.all(count[bnd] == 2)
    # The kite mesh has one element at each hexagon vertex (the corner that folds)
    _, kc, kb = ellipse_mesh(1.0, 1.0, level)
    assert np.sum(np.bincount(kc.ravel())[kb] == 1) == 6


def test_ring_quality_bounded_where_kites_degrade():
    ring = [jacobian_ratio(*ring_mesh(1.0, 1.0, n)[:2]).min() for n in LEVELS]
    kite = [jacobian_ratio(*ellipse_mesh(1.0, 1.0, n)[:2]).min() for n in LEVELS]
    # The ring mesh's worst corner-Jacobian ratio stays above 0.3 (the kite's falls as 1/n)
    assert min(ring) > 0.3
    assert kite[-1] < 0.05 and all(r > 2 * k for r, k in zip(ring, kite, strict=True))


def test_grain_mesh_dispatch():
    for kind in ("kite", "ring"):
        xy, conn, _ = grain_mesh(1.0, 1.0, 2, kind)
        assert conn.shape[0] == quads_per_grain(2, kind)
    assert np.array_equal(grain_mesh(1.0, 1.0, 3)[0], ellipse_mesh(1.0, 1.0, 3)[0])


def test_locate_inverts_the_bilinear_map():
    rng = np.random.default_rng(5)
    xy, conn, _ = ellipse_mesh(1.0, 0.6, 2)
    # Random natural points of random elements, mapped, then located again
    e = rng.integers(0, conn.shape[0], 50)
    xi, eta = rng.uniform(-0.9, 0.9, 50), rng.uniform(-0.9, 0.9, 50)
    pts = np.einsum("mk,mkd->md", shape(xi, eta), xy[conn[e]])
    e2, xi2, eta2 = locate(xy, conn, pts)
    assert np.array_equal(e2, e)
    assert np.allclose(xi2, xi, atol=1e-12) and np.allclose(eta2, eta, atol=1e-12)
    with pytest.raises(ValueError):
        locate(xy, conn, np.array([[2.0, 0.0]]))


def _deformed(n=4, level0=1, seed=3):
    """Kite meshes at level0 of n placed ellipses, every node moved a little at random."""
    rng = np.random.default_rng(seed)
    out = []
    for _ in range(n):
        a = rng.uniform(1e-4, 2e-4)
        xy, _, _ = ellipse_mesh(a, a * rng.uniform(0.6, 1.0), level0)
        xy = place(xy, rng.uniform(0, 1e-3, 2), rng.uniform(0, np.pi))
        out.append(xy + rng.normal(0.0, 0.04 * a, xy.shape))
    return np.array(out)


@pytest.mark.parametrize("level0,level", [(1, 1), (1, 2), (1, 3), (2, 4)])
def test_bed_onto_rings_keeps_polygon_and_area(level0, level):
    x0 = _deformed(level0=level0)
    _, conn0, _ = ellipse_mesh(1.0, 1.0, level0)
    _, conn, bnd = ring_mesh(1.0, 1.0, level)
    _, _, bnd_k = ellipse_mesh(1.0, 1.0, level)
    x = ring_nodes(x0, level0, level)
    fine = refine_nodes(x0, level0, level)
    for g in range(x0.shape[0]):
        # The boundary is the kite refinement's, bit for bit; the area the bed grain's
        assert np.array_equal(x[g][bnd], fine[g][bnd_k])
        assert areas(x[g], conn).sum() == pytest.approx(areas(x0[g], conn0).sum(), rel=1e-12)
        assert np.all(areas(x[g], conn) > 0.0)


def test_undeformed_bed_gives_the_ring_mesh():
    ref, _, _ = ellipse_mesh(1.0, 1.0, 2)
    ring, _, _ = ring_mesh(1.0, 1.0, 2)
    assert np.allclose(ring_nodes(ref[None], 2, 2)[0], ring, rtol=0, atol=1e-15)


def test_bed_points_onto_rings():
    # A parent element's four points carry four distinct values; each ring point takes the
    # value of the parent quadrant it lies in, a one-point ring element a parent's value
    level0, level = 1, 2
    rng = np.random.default_rng(2)
    vals = rng.normal(size=(2, 6, 4, 3))
    four = ring_points(vals, level0, level, 4)
    one = ring_points(vals, level0, level, 1)
    assert four.shape == (2, quads_per_grain(level, "ring"), 4, 3)
    assert one.shape == (2, quads_per_grain(level, "ring"), 1, 3)
    parents4 = refine_points(vals, level0, level, 4).reshape(2, -1, 3)
    parents1 = refine_points(vals, level0, level, 1).reshape(2, -1, 3)
    for g in range(2):
        assert all(any(np.array_equal(v, p) for p in parents4[g]) for v in four[g].reshape(-1, 3))
        assert all(any(np.array_equal(v, p) for p in parents1[g]) for v in one[g].reshape(-1, 3))
