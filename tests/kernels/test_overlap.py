"""Overlap geometry of quads and half-planes, and the contact candidate finders."""

import numpy as np
import pytest

from pdfem.kernels import broad_phase as BP
from pdfem.kernels import overlap as O
from tests.kernels.contact_helpers import SQ, random_quad, ref_polygon, rot, shoelace

# ---- helpers ----


def ref_overlap(p, q):
    """Brute overlap area and centroid (shoelace of ref_polygon)."""
    pts = ref_polygon(p, q)
    return shoelace(pts) if len(pts) else (0.0, np.zeros(2))


def grid_body(nx, ny, size, angle, shift, gid, node0):
    """A body meshed by nx x ny quads; returns x, conn (offset by node0), ebnd, egid, eloc."""
    gx, gy = np.meshgrid(np.linspace(0, nx * size, nx + 1), np.linspace(0, ny * size, ny + 1))
    x = np.c_[gx.ravel(), gy.ravel()] @ rot(angle).T + shift
    conn, ebnd = [], []
    for j in range(ny):
        for i in range(nx):
            n = j * (nx + 1) + i
            conn.append([n, n + 1, n + nx + 2, n + nx + 1])
            ebnd.append([j == 0, i == nx - 1, j == ny - 1, i == 0])
    ne = nx * ny
    return (
        x,
        np.array(conn, np.int64) + node0,
        np.array(ebnd, np.int8),
        np.full(ne, gid, np.int64),
        np.arange(ne, dtype=np.int64),
    )


# ---- overlap geometry ----


@pytest.mark.parametrize("d", [0.1, 0.25, 0.5, 0.7, 0.9])
def test_offset_unit_squares(d):
    buf = O.alloc_clip_buffers()
    st, area, cx, cy, c1x, c1y, c2x, c2y, k = O.quad_overlap(SQ, SQ + [d, 0.3], *buf)
    assert st == O.OV_OK and k == 4
    assert area == pytest.approx((1 - d) * 0.7, rel=1e-15, abs=0)
    assert (cx, cy) == pytest.approx(((1 + d) / 2, 0.65), rel=1e-15)
    # Chord joins the two boundary crossings; its clockwise normal points from A into B
    assert {(round(c1x, 12), c1y), (round(c2x, 12), c2y)} == {(1.0, 0.3), (round(d, 12), 1.0)}
    assert (c2y - c1y) > 0 and (c1x - c2x) > 0


def test_quad_overlap_matches_brute_force():
    rng = np.random.default_rng(1)
    buf = O.alloc_clip_buffers()
    nhit = 0
    for _ in range(2000):
        p, q = random_quad(rng), random_quad(rng)
        st, area, cx, cy, c1x, c1y, c2x, c2y, k = O.quad_overlap(p, q, *buf)
        ra, rc = ref_overlap(p, q)
        assert area == pytest.approx(ra, rel=1e-12, abs=1e-13)
        if st == O.OV_OK:
            nhit += 1
            assert (cx, cy) == pytest.approx(tuple(rc), rel=1e-10, abs=1e-12)
            # The chord normal agrees with the boundary-normal sum (A into B)
            sx, sy = O.boundary_normal_sum(*buf[:3], k)
            assert (c2y - c1y) * sx + (c1x - c2x) * sy > 0
            # Clipping is symmetric up to rounding
            assert O.quad_overlap(q, p, *buf)[1] == pytest.approx(area, rel=1e-12)
    assert nhit > 500


def test_quad_overlap_containment_and_disjoint():
    buf = O.alloc_clip_buffers()
    small = 0.25 + 0.5 * SQ
    assert O.quad_overlap(SQ, small, *buf)[0] == O.OV_INSIDE
    assert O.quad_overlap(small, SQ, *buf)[0] == O.OV_INSIDE
    assert O.quad_overlap(SQ, SQ + [2.0, 0.0], *buf)[:2] == (O.OV_NONE, 0.0)
    # Touching along an edge has zero area
    assert O.quad_overlap(SQ, SQ + [1.0, 0.5], *buf)[0] == O.OV_NONE


def test_star_overlap_has_eight_crossings():
    buf = O.alloc_clip_buffers()
    c = np.array([0.5, 0.5])
    q = (SQ - c) @ rot(np.pi / 4).T + c
    st, area, *_, k = O.quad_overlap(SQ, q, *buf)
    assert st == O.OV_OK and k == 8
    assert np.sum(buf[2][0, :k, O.T_KIND] == O.K_X) == 8
    assert area == pytest.approx(2 * (np.sqrt(2) - 1), rel=1e-14)


def test_halfplane_closed_form():
    buf = O.alloc_clip_buffers()
    # Diamond (square rotated 45 deg) with its lowest vertex h below the wall: area h^2
    dia = (SQ - 0.5) @ rot(np.pi / 4).T + [0.0, np.sqrt(0.5)]
    for h in [0.05, 0.2, 0.5]:
        st, area, cx, cy, c1x, c1y, c2x, c2y, k = O.halfplane_overlap(dia, 0.0, h, 0.0, 1.0,
                                                                           *buf)
        assert st == O.OV_OK
        assert area == pytest.approx(h * h, rel=1e-14)
        assert (cx, cy) == pytest.approx((0.0, 2 * h / 3), abs=1e-14)
        assert (c1y, c2y) == pytest.approx((h, h), rel=1e-15)
        # Chord normal (clockwise) is -n: from the element into the wall
        assert c2x - c1x > 0
    # Random quads against random walls: area of the part behind the wall
    rng = np.random.default_rng(2)
    for _ in range(300):
        p = random_quad(rng)
        a = rng.uniform(0, 2 * np.pi)
        n = np.array([np.cos(a), np.sin(a)])
        p0 = rng.uniform(-0.5, 0.5, 2)
        area = O.halfplane_overlap(p, *p0, *n, *buf)[1]
        big = np.array([[-1, -50], [1, -50], [1, 0], [-1, 0]]) * [50, 1]
        wall = big @ np.array([[n[1], -n[0]], [n[0], n[1]]]) + p0
        assert area == pytest.approx(ref_overlap(p, wall)[0], rel=1e-11, abs=1e-13)
    # Entirely behind the wall: guard
    st = O.halfplane_overlap(SQ, 0.0, 2.0, 0.0, 1.0, *buf)[0]
    assert st == O.OV_INSIDE


def test_early_out_keeps_the_clips_answer_for_a_non_convex_element():
    # B lies wholly outside one edge line of the dart-shaped A, yet inside A: the clip (A by
    # B's lines) finds the overlap, and the early out must not hide it
    from pdfem.kernels.overlap import outside_edge

    xa = np.array([[0.0, 0.0], [4.0, 0.0], [2.0, 1.0], [2.0, 3.0]])
    xb = np.array([[3.0544705, 0.6247629], [2.8157275, 0.85142066],
                   [2.58906975, 0.61267766], [2.82781274, 0.38601991]])
    assert outside_edge(xa, xb)
    st = O.quad_overlap(xa, xb, *O.alloc_clip_buffers())
    assert st[0] != O.OV_NONE and st[1] > 0.04
    # Far apart: the early out answers, with the clip's result (no overlap)
    st = O.quad_overlap(xa, xb + 10.0, *O.alloc_clip_buffers())
    assert st[0] == O.OV_NONE and st[1] == 0.0


def test_quad_overlap_area_is_the_clip_and_classify_of_the_general_path():
    # The contact kernel's status, area and centroid equal those of clipping A by B and
    # classifying the polygon with its chord (classify), on random pairs, containment and
    # near misses
    rng = np.random.default_rng(11)
    buf, buf2 = O.alloc_clip_buffers(), O.alloc_clip_buffers()
    small = 0.25 * SQ + 0.3
    cases = [(random_quad(rng), random_quad(rng)) for _ in range(3000)]
    cases += [(SQ, small), (small, SQ), (SQ, SQ + [2.0, 0.0]), (SQ, SQ + [1.0, 0.5])]
    seen = set()
    for p, q in cases:
        k0 = O.clip_convex(p, 4, q, 4, *buf)
        ref = O.classify(buf[0], buf[1], buf[2], k0, O.bbox_scale2(p))
        st, area, cx, cy, k = O.quad_overlap_area(p, q, *buf2)
        assert (st, area, cx, cy) == ref[:4]
        if st != O.OV_NONE:
            assert k == k0 and np.array_equal(buf[0][0, :k], buf2[0][0, :k])
            # quad_overlap adds the chord of the same polygon
            assert O.quad_overlap(p, q, *buf2)[4:8] == ref[4:8]
        seen.add(st)
    assert {O.OV_OK, O.OV_NONE, O.OV_INSIDE} <= seen


# ---- candidate finders ----


def test_candidate_pairs_equal_brute_force():
    rng = np.random.default_rng(5)
    xs, conns, ebnds, gids, elocs, e0, e1 = [], [], [], [], [], [], []
    nn = ne = 0
    gperm = rng.permutation(40)
    for b in range(40):
        nx, ny = rng.integers(1, 4, 2)
        x, conn, eb, eg, el = grid_body(
            nx, ny, rng.uniform(0.2, 0.5), rng.uniform(0, 6.3), rng.uniform(0, 6, 2), gperm[b], nn
        )
        xs.append(x)
        conns.append(conn)
        ebnds.append(eb)
        gids.append(eg)
        elocs.append(el)
        e0.append(ne)
        ne += len(conn)
        nn += len(x)
        e1.append(ne)
    x, conn = np.vstack(xs), np.vstack(conns)
    ebnd, egid, eloc = np.vstack(ebnds), np.concatenate(gids), np.concatenate(elocs)
    ebnd[rng.random(ebnd.shape) < 0.1] = 0
    bbox = np.zeros((ne, 4))
    BP.element_bboxes(x, conn, 0, ne, bbox)
    assert np.array_equal(bbox[:, :2], np.stack([x[conn].min(1)[:, i] for i in (0, 1)], 1))
    skin = 0.1
    out = np.zeros((10, 2), np.int64)
    n = BP.pairs_from_bboxes(bbox, ebnd, egid, eloc, 0, ne, skin, out)
    assert n > 10
    brute = np.zeros((n, 2), np.int64)
    assert BP.pairs_from_bboxes(bbox, ebnd, egid, eloc, 0, ne, skin, brute) == n
    bp = np.array([(i, j) for i in range(40) for j in range(i + 1, 40)], np.int64)
    bp[::2] = bp[::2, ::-1]
    cand = np.zeros((n + 5, 2), np.int64)
    assert (
        BP.candidate_pairs(bbox, ebnd, egid, eloc, np.array(e0), np.array(e1), bp, skin, False,
                           0.0, cand) == n
    )
    cand = cand[:n]
    assert {tuple(p) for p in brute} == {tuple(p) for p in cand}
    # Oriented lower body gid first, boundary elements only, near within skin
    assert np.all(egid[cand[:, 0]] < egid[cand[:, 1]])
    assert np.all(ebnd[cand].reshape(n, -1).any(1))
    gap = np.maximum(
        bbox[cand[:, 0], :2] - bbox[cand[:, 1], 2:], bbox[cand[:, 1], :2] - bbox[cand[:, 0], 2:]
    )
    assert np.all(gap <= skin)
    # Every element pair that overlaps (no skin) is a candidate
    buf = O.alloc_clip_buffers()
    cset = {tuple(p) for p in cand}
    for i in range(ne):
        for j in range(ne):
            if egid[i] < egid[j] and ebnd[i].any() and ebnd[j].any():
                if O.quad_overlap(x[conn[i]], x[conn[j]], *buf)[0] != O.OV_NONE:
                    assert (i, j) in cset
    # deep (the potential law): also a boundary element with any element of the other body,
    # exactly the pairs of elements of two bodies, one on its boundary, within skin
    deep = np.zeros((4 * n + 5, 2), np.int64)
    nd = BP.candidate_pairs(bbox, ebnd, egid, eloc, np.array(e0), np.array(e1), bp, skin, True,
                            0.0, deep)
    want = {(i, j) for i in range(ne) for j in range(ne)
            if egid[i] < egid[j] and (ebnd[i].any() or ebnd[j].any())
            and BP.boxes_near(bbox[i], bbox[j], skin)}
    assert nd > n and {tuple(p) for p in deep[:nd]} == want
