"""Tests of the grain meshes (ellipse, block) and the quad quality measures."""

import numpy as np
import pytest

from pdfem.mesh.block import block_mesh
from pdfem.mesh.ellipse import ellipse_mesh, place
from pdfem.mesh.quality import areas, boundary_edges, corner_jacobians, jacobian_ratio

LEVELS = [1, 2, 3, 4]
ASPECTS = [1.0, 2.0, 4.0]


def _shoelace(xy, loop):
    """Area enclosed by a closed polygon given as a node loop (positive if CCW)."""
    p = xy[loop]
    q = np.roll(p, -1, axis=0)
    return 0.5 * np.sum(p[:, 0] * q[:, 1] - p[:, 1] * q[:, 0])


def _gauss_ratio(xy, conn):
    """min/max of det J over the 2x2 Gauss points (det J is bilinear in xi, eta: exact)."""
    det = corner_jacobians(xy, conn)
    g = 1.0 / np.sqrt(3.0)
    vals = []
    for xi, eta in [(-g, -g), (g, -g), (g, g), (-g, g)]:
        along_xi = np.array([1 - xi, 1 + xi, 1 + xi, 1 - xi])
        along_eta = np.array([1 - eta, 1 - eta, 1 + eta, 1 + eta])
        vals.append(det @ (along_xi * along_eta / 4.0))
    vals = np.array(vals)
    return vals.min(axis=0) / vals.max(axis=0)


@pytest.mark.parametrize("level", LEVELS + [5, 8])
def test_ellipse_counts(level):
    xy, conn, boundary = ellipse_mesh(2.0e-3, 1.0e-3, level)
    assert conn.shape == (6 * level**2, 4)
    assert xy.shape == (1 + 6 * level * (level + 1), 2)
    assert boundary.shape == (12 * level,)
    assert xy.dtype == np.float64 and conn.dtype == np.int64 and boundary.dtype == np.int64
    # Every node is used, the boundary loop has no repeats and starts at (a, 0)
    assert np.array_equal(np.unique(conn), np.arange(len(xy)))
    assert len(np.unique(boundary)) == len(boundary)
    assert np.allclose(xy[boundary[0]], [2.0e-3, 0.0], rtol=0, atol=1e-18)


def test_ellipse_area_converges():
    a, b = 3.0e-3, 1.5e-3
    errors = []
    for level in LEVELS + [8]:
        xy, conn, boundary = ellipse_mesh(a, b, level)
        area = areas(xy, conn)
        # All positive, and the mesh fills exactly its boundary polygon
        assert np.all(area > 0.0)
        assert np.isclose(area.sum(), _shoelace(xy, boundary), rtol=1e-13, atol=0)
        errors.append(abs(area.sum() - np.pi * a * b) / (np.pi * a * b))
    # Inscribed polygon: error decreasing, O(1/n^2)
    assert all(e1 < e0 for e0, e1 in zip(errors, errors[1:], strict=False))
    assert errors[-1] < 1e-3


@pytest.mark.parametrize("level", LEVELS)
def test_ellipse_boundary_on_curve_and_ccw(level):
    a, b = 4.0e-3, 1.0e-3
    xy, conn, boundary = ellipse_mesh(a, b, level)
    p = xy[boundary]
    assert np.max(np.abs((p[:, 0] / a) ** 2 + (p[:, 1] / b) ** 2 - 1.0)) < 1e-12
    # Counter-clockwise loop with monotone polar angle
    assert _shoelace(xy, boundary) > 0.0
    ang = np.unwrap(np.arctan2(p[:, 1] / b, p[:, 0] / a))
    assert np.all(np.diff(ang) > 0.0)
    # Closing gap at V_0 is at most the mean gap 2 pi / (12 n) (equal for n = 1)
    assert 2 * np.pi * (1 - 1 / (12 * level)) - 1e-12 < ang[-1] - ang[0] < 2 * np.pi


@pytest.mark.parametrize("level", LEVELS)
def test_ellipse_no_duplicate_nodes(level):
    a, b = 2.0e-3, 0.5e-3
    xy, _, _ = ellipse_mesh(a, b, level)
    d = np.linalg.norm(xy[:, None, :] - xy[None, :, :], axis=-1)
    d[np.diag_indices(len(xy))] = np.inf
    # Smallest spacing is a fair fraction of b / n, far above any rounding
    assert d.min() > 0.1 * b / level


@pytest.mark.parametrize("level", LEVELS + [5, 8])
def test_ellipse_boundary_edges(level):
    xy, conn, boundary = ellipse_mesh(1.0, 0.5, level)
    be = boundary_edges(conn)
    assert be.shape == (12 * level, 2)
    # The boundary edges are exactly the consecutive pairs of the boundary loop
    start = conn[be[:, 0], be[:, 1]]
    end = conn[be[:, 0], (be[:, 1] + 1) % 4]
    loop = {(int(p), int(q)) for p, q in zip(boundary, np.roll(boundary, -1), strict=True)}
    assert {(int(p), int(q)) for p, q in zip(start, end, strict=True)} == loop


def test_ellipse_jacobian_ratio():
    """Corner Jacobian ratio of the ellipse meshes, per level and aspect ratio a/b.

    Scaling by (a, b) multiplies det J by a b everywhere, so the ratio does not depend on the
    aspect ratio. Only the 6n elements on the kite diagonals (j == k, the rays through the
    hexagon vertices, where the radial map has a kink) degrade; the worst is the element at
    each vertex V_i, a boundary node with a single element: its two boundary edges are chords
    of the smooth curve, so its corner angle is 180 deg - O(1/n) and its ratio is about
    0.18/n (measured 0.155 n=1, 0.169 n=2, 0.174 n=3, 0.176 n=4, 0.181 n=8, times 1/n).
    Off-diagonal elements stay above 0.73, and the ratio over the 2x2 Gauss points (what the
    integrator sees) stays above 0.28 up to n = 8 (0.289; 0.279 n=16, 0.271 n=64).
    """
    rows = []
    for level in LEVELS + [8]:
        ref = None
        for aspect in ASPECTS:
            xy, conn, _ = ellipse_mesh(aspect * 1.0e-3, 1.0e-3, level)
            ratio = jacobian_ratio(xy, conn)
            rows.append((level, aspect, ratio.min(), _gauss_ratio(xy, conn).min()))
            # Aspect independence
            if ref is None:
                ref = ratio
            assert np.allclose(ratio, ref, rtol=1e-12, atol=0)
            # Bounds: worst element ~ 0.18/n, off-diagonal elements well shaped
            assert level * ratio.min() > 0.15
            local = np.arange(len(conn)) % (level * level)
            off_diagonal = local // level != local % level
            if level > 1:
                assert ratio[off_diagonal].min() > 0.7
            assert _gauss_ratio(xy, conn).min() > 0.28
    print("\nlevel aspect min_corner_jacobian_ratio min_gauss_jacobian_ratio")
    for level, aspect, rmin, gmin in rows:
        print(f"{level:5d} {aspect:6.1f} {rmin:26.4f} {gmin:25.4f}")


def test_place():
    xy, conn, boundary = ellipse_mesh(2.0, 1.0, 2)
    copy = xy.copy()
    moved = place(xy, (10.0, -5.0), np.pi / 2)
    # Centre goes to the new centre, (a, 0) rotates onto (0, a)
    assert np.allclose(moved[0], [10.0, -5.0])
    assert np.allclose(moved[boundary[0]], [10.0, -3.0])
    # Rigid: areas kept, still counter-clockwise; input untouched
    assert np.allclose(areas(moved, conn), areas(xy, conn))
    assert np.array_equal(xy, copy)


@pytest.mark.parametrize("level", [0, -1, 1.5])
def test_ellipse_bad_level(level):
    with pytest.raises(ValueError, match="level"):
        ellipse_mesh(1.0, 1.0, level)


@pytest.mark.parametrize("nx,ny", [(1, 1), (3, 1), (4, 3)])
def test_block_mesh(nx, ny):
    x0, y0, x1, y1 = -1.0e-3, 2.0e-3, 5.0e-3, 3.0e-3
    xy, conn, boundary, sets = block_mesh(x0, y0, x1, y1, nx, ny)
    assert xy.shape == ((nx + 1) * (ny + 1), 2)
    assert conn.shape == (nx * ny, 4)
    # Counter-clockwise, equal areas filling the rectangle, unit Jacobian ratio
    area = areas(xy, conn)
    assert np.allclose(area, (x1 - x0) * (y1 - y0) / (nx * ny))
    assert np.allclose(jacobian_ratio(xy, conn), 1.0)
    # Boundary loop: CCW, starts at (x0, y0), 2 (nx + ny) nodes
    assert boundary.shape == (2 * (nx + ny),)
    assert np.allclose(xy[boundary[0]], [x0, y0])
    assert np.isclose(_shoelace(xy, boundary), (x1 - x0) * (y1 - y0))
    # Node sets, corners in both adjacent sets
    assert np.array_equal(sets["bottom"], np.flatnonzero(xy[:, 1] == y0))
    assert np.array_equal(sets["top"], np.flatnonzero(xy[:, 1] == y1))
    assert np.array_equal(sets["left"], np.flatnonzero(xy[:, 0] == x0))
    assert np.array_equal(sets["right"], np.flatnonzero(xy[:, 0] == x1))
    assert np.array_equal(sets["all"], np.arange(len(xy)))
    assert np.intersect1d(sets["left"], sets["bottom"]).tolist() == [0]
    for s in sets.values():
        assert s.dtype == np.int64 and np.all(np.diff(s) > 0)
    # Boundary edges
    be = boundary_edges(conn)
    assert be.shape == (2 * (nx + ny), 2)
    assert set(np.unique(conn[be[:, 0], be[:, 1]])) == set(boundary.tolist())


def test_block_mesh_explicit():
    xy, conn, boundary, sets = block_mesh(0.0, 0.0, 3.0, 1.0)
    assert conn.tolist() == [[0, 1, 5, 4], [1, 2, 6, 5], [2, 3, 7, 6]]
    assert boundary.tolist() == [0, 1, 2, 3, 7, 6, 5, 4]
    assert sets["left"].tolist() == [0, 4] and sets["right"].tolist() == [3, 7]
    assert sets["bottom"].tolist() == [0, 1, 2, 3] and sets["top"].tolist() == [4, 5, 6, 7]
    expected = [[0, 0], [0, 2], [0, 3], [1, 0], [1, 2], [2, 0], [2, 1], [2, 2]]
    assert boundary_edges(conn).tolist() == expected


def test_quality_distorted_quad():
    # A trapezoid: exact area and corner Jacobians
    xy = np.array([[0.0, 0.0], [4.0, 0.0], [3.0, 1.0], [1.0, 1.0]])
    conn = np.array([[0, 1, 2, 3]])
    assert np.isclose(areas(xy, conn)[0], 3.0)
    assert np.allclose(corner_jacobians(xy, conn)[0], [1.0, 1.0, 0.5, 0.5])
    assert np.isclose(jacobian_ratio(xy, conn)[0], 0.5)
    # Clockwise ordering gives negative area and ratio
    assert areas(xy, conn[:, ::-1])[0] < 0.0
    assert np.isclose(jacobian_ratio(xy, conn[:, ::-1])[0], -1.0)
    # Non-convex (dart) quad: one negative corner
    dart = np.array([[0.0, 0.0], [2.0, 1.0], [0.0, 2.0], [1.0, 1.0]])
    assert jacobian_ratio(dart, conn)[0] < 0.0


def test_point_jacobians_corners_and_parallelogram():
    from pdfem.mesh.quality import corner_jacobians, point_jacobians

    # A skewed, tapered quad: at the corners the same as corner_jacobians
    xy = np.array([[0.0, 0.0], [2.0, 0.1], [2.5, 1.4], [0.2, 1.0]])
    conn = np.array([[0, 1, 2, 3]])
    corners = [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)]
    assert np.allclose(point_jacobians(xy, conn, corners), corner_jacobians(xy, conn),
                       rtol=1e-14)
    # A parallelogram: constant, a quarter of its area, at any point
    par = np.array([[0.0, 0.0], [2.0, 0.0], [2.5, 1.0], [0.5, 1.0]])
    j = point_jacobians(par, conn, [(0.0, 0.0), (0.3, -0.7), (0.577, 0.577)])
    assert np.allclose(j, 2.0 / 4.0, rtol=1e-14)
