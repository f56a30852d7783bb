"""A bed re-meshed at a finer level: same polygons and area, valid quads, the numbering of
ellipse_mesh, stresses carried from the parent elements."""

import h5py
import numpy as np
import pytest

from pdfem.errors import InputError
from pdfem.io.bedfile import read_bed, write_bed
from pdfem.mesh.ellipse import _kite_numbering, ellipse_mesh, place
from pdfem.prepare.relevel import refine_nodes, refine_points, relevel_bed
from pdfem.scene.values import SceneError
from pdfem.tools.analysis.runfile import element_areas


def _deformed_grains(n=5, seed=3):
    """Level-1 meshes of n placed ellipses, each node moved a little at random."""
    rng = np.random.default_rng(seed)
    out = []
    for _ in range(n):
        a = rng.uniform(1e-4, 2e-4)
        xy, _, _ = ellipse_mesh(a, a * rng.uniform(0.6, 1.0), 1)
        xy = place(xy, rng.uniform(0, 1e-3, 2), rng.uniform(0, np.pi))
        out.append(xy + rng.normal(0.0, 0.05 * a, xy.shape))
    return np.array(out)


@pytest.mark.parametrize("level", [2, 3, 4])
def test_refined_mesh_keeps_area_and_is_valid(level):
    x1 = _deformed_grains()
    _, conn1, _ = ellipse_mesh(1.0, 1.0, 1)
    _, conn, boundary = ellipse_mesh(1.0, 1.0, level)
    x = refine_nodes(x1, 1, level)
    assert x.shape == (x1.shape[0], 1 + 6 * level * (level + 1), 2)
    for g in range(x1.shape[0]):
        areas = element_areas(x[g], conn)
        # Same total area (the same polygon, tiled exactly) and every quad positive
        total1 = element_areas(x1[g], conn1).sum()
        assert areas.sum() == pytest.approx(total1, rel=1e-12)
        assert np.all(areas > 0.0)
        # The boundary loop of ellipse_mesh at this level encloses that area too
        bx, by = x[g][boundary, 0], x[g][boundary, 1]
        loop = 0.5 * np.sum(bx * np.roll(by, -1) - np.roll(bx, -1) * by)
        assert loop == pytest.approx(total1, rel=1e-12)


@pytest.mark.parametrize("level", [2, 3, 4])
def test_refined_mesh_follows_the_kite_numbering(level):
    x1 = _deformed_grains(2)
    x = refine_nodes(x1, 1, level)
    idx1, idx = _kite_numbering(1), _kite_numbering(level)
    # Every level-1 node is the level-L node at the same (kite, s, t)
    for i in range(6):
        for j in range(2):
            for k in range(2):
                assert np.array_equal(x[:, idx[i, j * level, k * level]], x1[:, idx1[i, j, k]])
    # Nested refinement agrees (the kites' bilinear maps are refined exactly)
    if level == 4:
        assert np.allclose(refine_nodes(refine_nodes(x1, 1, 2), 2, 4), x, rtol=0, atol=1e-18)


def test_undeformed_level_1_mesh_refines_onto_its_polygon():
    # Boundary nodes of the refined mesh lie on the straight level-1 boundary edges
    xy1, _, b1 = ellipse_mesh(2e-4, 1e-4, 1)
    x = refine_nodes(xy1[None], 1, 3)[0]
    _, _, b3 = ellipse_mesh(2e-4, 1e-4, 3)
    poly = xy1[b1]
    for p in x[b3]:
        d = []
        for a, b in zip(poly, np.roll(poly, -1, axis=0), strict=True):
            t = np.clip(np.dot(p - a, b - a) / np.dot(b - a, b - a), 0.0, 1.0)
            d.append(np.hypot(*(a + t * (b - a) - p)))
        assert min(d) < 1e-16


def test_stresses_go_to_the_sub_elements():
    # Parent element e, point p holds 10 e + p
    vals = (10.0 * np.arange(6)[:, None] + np.arange(4)[None, :])[None, :, :, None]
    assert np.array_equal(refine_points(vals, 1, 1, 4), vals)
    two = refine_points(vals, 1, 2, 4)[0, :, :, 0]
    # Level 2: kite i cell (j, k) is element 4 i + 2 j + k; sub-cell (a, b) of the parent
    # takes the parent point of its quadrant (0: a=b=0, 1: a=1 b=0, 2: a=b=1, 3: a=0 b=1)
    for i in range(6):
        for (a, b), p in {(0, 0): 0, (1, 0): 1, (1, 1): 2, (0, 1): 3}.items():
            assert np.all(two[4 * i + 2 * a + b] == 10 * i + p)
    # Level 3: the middle sub-element's points fall in the four quadrants, in order
    three = refine_points(vals, 1, 3, 4)[0, :, :, 0]
    assert np.array_equal(three[9 * 2 + 3 * 1 + 1], 10 * 2 + np.arange(4))
    # To the 1-point rule: the parent's mean
    one = refine_points(vals, 1, 2, 1)
    assert one.shape == (1, 24, 1, 1)
    assert np.allclose(one[0, :4, 0, 0], 1.5)


def test_relevel_bed_round_trip(tmp_path):
    x1 = _deformed_grains(3)
    ell = np.zeros((3, 5))
    stress = np.random.default_rng(0).normal(size=(3, 6, 4, 4))
    state = np.random.default_rng(1).normal(size=(3, 6, 4, 6))
    src = str(tmp_path / "bed.h5")
    write_bed(src, ell, x1, np.zeros_like(x1), {"level": 1, "packing_fraction": 0.8},
              stress, state)
    dst = relevel_bed(src, str(tmp_path / "bed3.h5"), 3, "1pt")
    cols, nodes, vel, level, sig, mst = read_bed(dst, "bed3.h5")
    assert level == 3 and nodes.shape == (3, 73, 2) and vel.shape == nodes.shape
    assert sig.shape == (3, 54, 1, 4) and mst.shape == (3, 54, 1, 6)
    assert np.allclose(sig[:, 0, 0], stress[:, 0].mean(axis=1))
    with h5py.File(dst) as f:
        assert f.attrs["relevelled_from"] == 1 and f.attrs["packing_fraction"] == 0.8
    # Only multiples of the bed's level
    write_bed(str(tmp_path / "bed2.h5"), ell, refine_nodes(x1, 1, 2),
              np.zeros((3, 37, 2)), {"level": 2})
    with pytest.raises(SceneError, match="not a multiple"):
        relevel_bed(str(tmp_path / "bed2.h5"), str(tmp_path / "x.h5"), 3)


def test_scene_subdivides_a_coarser_bed(tmp_path):
    """A scene at level 2 loads a level-1 bed by subdividing its meshes in place (the same as
    relevel_bed writes); a level that is not a multiple of the bed's is refused."""
    from pdfem.scene import parse_scene
    from tests.scenes import packaged

    doc = packaged("shot912_small.toml")
    src = doc["grains_file"]["path"]
    doc["element"] = {"rule": "1pt", "level": 2}
    sc = parse_scene(doc, str(tmp_path))
    relevel_bed(src, str(tmp_path / "l2.h5"), 2, "1pt")
    _, x2, _, level, _, _ = read_bed(str(tmp_path / "l2.h5"), "l2")
    assert level == 2 and np.array_equal(sc.grains["nodes"], x2)
    doc["element"]["level"] = 3
    doc["grains_file"]["path"] = str(tmp_path / "l2.h5")
    with pytest.raises(InputError, match="element.level: must be a multiple of 2"):
        parse_scene(doc, str(tmp_path))
