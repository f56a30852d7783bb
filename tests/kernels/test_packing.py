"""Packing and polygon kernels (pdfem.kernels.packing, .polygon) against closed forms and
brute force."""

import math

import numpy as np
import pytest

from pdfem.kernels.cell_list import build_cells
from pdfem.kernels.packing import (
    grow_sweep,
    mc_sweep,
    min_pair_scale,
    pair_limit,
    pair_scale,
    rotate_into,
    wall_scale,
)
from pdfem.kernels.polygon import polygon_gap, slab_area, slab_areas


def square(h, angle=0.0):
    """Vertices (4, 2) of a square of half side h about the origin, counter-clockwise."""
    v = np.array([[-h, -h], [h, -h], [h, h], [-h, h]], float)
    out = np.empty_like(v)
    rotate_into(v, angle, out)
    return out


def ngon(r, n, angle=0.0):
    """Regular n-gon of circumradius r, counter-clockwise."""
    t = angle + 2.0 * np.pi * np.arange(n) / n
    return np.stack([r * np.cos(t), r * np.sin(t)], axis=1)


def overlap_sat(ca, va, cb, vb):
    """Do the convex polygons c + v overlap (separating axis theorem, brute force)?"""
    pa, pb = ca + va, cb + vb
    for poly in (pa, pb):
        for k in range(len(poly)):
            e = poly[(k + 1) % len(poly)] - poly[k]
            n = np.array([e[1], -e[0]])
            if (pa @ n).max() < (pb @ n).min() or (pb @ n).max() < (pa @ n).min():
                return False
    return True


def test_pair_scale_of_squares():
    """Axis-aligned squares of half side h, centres d apart along x: touch at s = d / 2h; a
    45 degree square against an aligned one: s = d / (h + h sqrt 2)."""
    h, d = 1.0e-4, 3.0e-4
    a = square(h)
    assert pair_scale(0.0, 0.0, a, d, 0.0, a) == pytest.approx(d / (2 * h), rel=1e-14)
    b = square(h, np.pi / 4)
    assert pair_scale(0.0, 0.0, a, d, 0.0, b) == pytest.approx(d / (h + h * np.sqrt(2)),
                                                               rel=1e-14)


def test_pair_scale_against_bisection():
    """Random pairs of polygons: overlapping just above s_ij, apart just below it."""
    rng = np.random.default_rng(3)
    for _ in range(200):
        va = ngon(1.0, 12, rng.uniform(0, 1)) * [rng.uniform(0.5, 1.5), rng.uniform(0.5, 1.5)]
        vb = ngon(1.0, 12, rng.uniform(0, 1)) * [rng.uniform(0.5, 1.5), rng.uniform(0.5, 1.5)]
        cb = rng.uniform(-4, 4, 2)
        s = pair_scale(0.0, 0.0, va, cb[0], cb[1], vb)
        assert overlap_sat(np.zeros(2), va * s * 1.000001, cb, vb * s * 1.000001)
        assert not overlap_sat(np.zeros(2), va * s * 0.999999, cb, vb * s * 0.999999)


def test_pair_limit_is_consistent_with_pair_scale():
    """With the neighbour at the common contact scale, the limit of the other is that scale;
    a smaller neighbour leaves more room."""
    rng = np.random.default_rng(5)
    for _ in range(50):
        va, vb = ngon(1.0, 12, rng.uniform(0, 1)), ngon(0.7, 12, rng.uniform(0, 1))
        cb = rng.uniform(-3, 3, 2)
        s = pair_scale(0.0, 0.0, va, cb[0], cb[1], vb)
        assert pair_limit(0.0, 0.0, va, cb[0], cb[1], vb, s) == pytest.approx(s, rel=1e-12)
        assert pair_limit(0.0, 0.0, va, cb[0], cb[1], vb, 0.5 * s) > s


def test_wall_scale_of_a_square():
    """A square of half side h at (x, y) in the unit box: limited by the nearest wall."""
    v = square(0.1)
    assert wall_scale(0.3, 0.6, v, 0.0, 0.0, 1.0, 1.0) == pytest.approx(3.0)
    assert wall_scale(0.5, 0.95, v, 0.0, 0.0, 1.0, 1.0) == pytest.approx(0.5)


def test_slab_area_closed_forms():
    """A unit square cut by horizontal slabs; a regular 12-gon inside a slab; halves add up."""
    sq = square(0.5) + 0.5
    wa, wb = np.empty((12, 2)), np.empty((12, 2))
    assert slab_area(sq, 0.2, 0.7, wa, wb) == pytest.approx(0.5)
    assert slab_area(sq, -1.0, 0.25, wa, wb) == pytest.approx(0.25)
    assert slab_area(sq, 2.0, 3.0, wa, wb) == 0.0
    # A diamond (square at 45 degrees, half diagonal 1): the band |y| <= 0.5 holds 3/4
    dia = square(1.0 / np.sqrt(2.0), np.pi / 4)
    assert slab_area(dia, -0.5, 0.5, wa, wb) == pytest.approx(1.5)
    g = ngon(1.0, 12, 0.3)
    w2 = np.empty((28, 2)), np.empty((28, 2))
    full = 0.5 * 12 * np.sin(2 * np.pi / 12)
    assert slab_area(g, -2.0, 2.0, *w2) == pytest.approx(full, rel=1e-14)
    polys = np.array([g, g[::-1]])
    out = np.empty(2)
    slab_areas(polys, -2.0, 0.1, out)
    low = out.copy()
    slab_areas(polys, 0.1, 2.0, out)
    assert np.allclose(low + out, full, rtol=1e-13)


def test_polygon_gap():
    """Two unit squares 0.3 apart along x; the same offset diagonally: corner to corner."""
    a = square(0.5)
    assert polygon_gap(a, a + [1.3, 0.0]) == pytest.approx(0.3)
    assert polygon_gap(a, a + [1.3, 1.4]) == pytest.approx(np.hypot(0.3, 0.4))


def _bed(n, seed):
    """n 12-gons on a lattice in the unit box, random angles; at full size they overlap."""
    rng = np.random.default_rng(seed)
    cols = int(math.ceil(math.sqrt(n)))
    cx = np.array([(i % cols + 0.5) / cols for i in range(n)])
    cy = np.array([(i // cols + 0.5) / cols for i in range(n)])
    base = np.array([ngon(0.6 / cols, 12) * [1.0, rng.uniform(0.6, 1.0)] for _ in range(n)])
    angle = rng.uniform(0, np.pi, n)
    verts = np.empty_like(base)
    for i in range(n):
        rotate_into(base[i], angle[i], verts[i])
    return cx, cy, angle, base, verts, np.sqrt((base ** 2).sum(2)).max(1)


def test_moves_and_growth_never_overlap():
    """Monte Carlo sweeps and per-grain growth keep every pair and wall apart (checked by the
    exact common contact scale and by brute force), and growth grows."""
    n = 25
    cx, cy, angle, base, verts, rad = _bed(n, 1)
    box = np.array([0.0, 0.0, 1.0, 1.0])
    h = 2.0 * rad.max() + 2.0 * np.sqrt(2.0) * 0.05
    nx = ny = max(1, int(1.0 / h))
    h = 1.0 / nx
    cell, start, items = np.empty(n, np.int64), np.zeros(nx * ny + 1, np.int64), \
        np.empty(n, np.int64)
    scale = np.full(n, 0.5)
    rng = np.random.default_rng(2)
    trial = np.empty_like(base[0])
    grown = []
    for _ in range(30):
        build_cells(cx, cy, 0.0, 0.0, h, nx, ny, cell, start, items)
        mc_sweep(cx, cy, angle, verts, base, rad, scale, rng.random((n, 4)), 0.02, box, cell,
                 start, items, nx, ny, trial, np.zeros(1), np.zeros(0), 0.0, 0.0)
        build_cells(cx, cy, 0.0, 0.0, h, nx, ny, cell, start, items)
        grown.append(grow_sweep(cx, cy, verts, rad, scale, 0.05, box, cell, start, items, nx,
                                ny))
    assert 0.5 < grown[0] < grown[-1] < 1.0
    for i in range(n):
        for j in range(i + 1, n):
            assert not overlap_sat(np.array([cx[i], cy[i]]), verts[i] * scale[i],
                                   np.array([cx[j], cy[j]]), verts[j] * scale[j])
    # At the smallest scale everything is apart: the common contact scale exceeds it
    build_cells(cx, cy, 0.0, 0.0, h, nx, ny, cell, start, items)
    assert min_pair_scale(cx, cy, verts * scale.min(), rad * scale.min(), box, cell, start,
                          items, nx, ny) > 1.0
