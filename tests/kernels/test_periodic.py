"""Periodic sides in the kernels: the contact pass meets a pair's second element shifted by
whole periods, the broad phase finds pairs across the seam and keeps each shift with its
orientation, the cell grid wraps, and tied block nodes move as one."""

import numpy as np

from partition.grid import CellGrid
from pdfem.build import joint_masses, tied_nodes
from pdfem.kernels import broad_phase as BP
from pdfem.kernels import contact as C
from pdfem.kernels.integrate import NACC, advance_velocities
from pdfem.kernels.neighbours import grain_pairs
from pdfem.mesh.block import block_mesh
from tests.kernels.test_contact import law_params, pass_args, random_pairs

W = 7.5  # the period of the kernel tests [m]


def test_contact_pass_meets_the_second_element_k_periods_away():
    # Random overlapping pairs pulled apart by k periods (k = -2..2), half of them given in the
    # reverse orientation with -k: every output equals, bit for bit, the pass over the
    # coordinates with B moved back by k W (the same float operation, x + k W)
    rng = np.random.default_rng(31)
    x, conn, ebnd, egid, eloc, elen, pairs = random_pairs(rng, 200)
    k = rng.integers(-2, 3, 200)
    far = x.copy()
    for p in range(200):
        far[conn[pairs[p, 1]], 0] -= k[p] * W
    near = far.copy()
    for p in range(200):
        near[conn[pairs[p, 1]], 0] = far[conn[pairs[p, 1]], 0] + k[p] * W
    cand = np.column_stack([pairs, k])
    cand[::2] = np.column_stack([pairs[::2, ::-1], -k[::2]])
    par = law_params(200, dmax=2.0, ks=2e9, zeta=0.4)
    us = rng.normal(0, 1e-5, 200)
    args, shifted = pass_args(far, conn, ebnd, egid, eloc, elen, cand, par, us=us)
    C.contact_pass(*args, *shifted, W)
    ref_cand = cand[:, :2].copy()
    args, ref = pass_args(near, conn, ebnd, egid, eloc, elen, ref_cand, par, us=us)
    C.contact_pass(*args, *ref)
    assert np.sum(ref[0] == C.C_ACTIVE) > 100 and np.count_nonzero(k) > 100
    for a, b in zip(shifted, ref, strict=True):
        assert a.tobytes() == b.tobytes()
    # Without the period the pairs lie apart and do not touch
    args, apart = pass_args(far, conn, ebnd, egid, eloc, elen, cand, par, us=us)
    C.contact_pass(*args, *apart)
    assert np.all(apart[0][k != 0] == C.C_NONE)


def test_candidate_pairs_keep_the_shift_with_the_orientation():
    # Two unit squares, the second (body 1) a period to the left: met a period to the right of
    # body 0, (0, 1, +1); given as (1, 0, -1) (body 0 a period to the left of body 1) the pair
    # comes out lower key first, (0, 1, +1); with k = 0 none
    x = np.array([[0.0, 0], [1, 0], [1, 1], [0, 1], [0.5 - W, 0.5], [1.5 - W, 0.5],
                  [1.5 - W, 1.5], [0.5 - W, 1.5]])
    conn = np.arange(8, dtype=np.int64).reshape(2, 4)
    ebnd = np.ones((2, 4), np.int8)
    egid, eloc = np.array([0, 1], np.int64), np.zeros(2, np.int64)
    bbox = np.empty((2, 4))
    BP.element_bboxes(x, conn, 0, 2, bbox)
    e0, e1 = np.array([0, 1], np.int64), np.array([1, 2], np.int64)
    for bpairs in ([[1, 0, -1]], [[0, 1, 1]]):
        out = np.zeros((4, 3), np.int64)
        n = BP.candidate_pairs(bbox, ebnd, egid, eloc, e0, e1, np.array(bpairs, np.int64), 0.0,
                               False, W, out)
        assert n == 1 and out[0].tolist() == [0, 1, 1]
    out = np.zeros((4, 3), np.int64)
    assert BP.candidate_pairs(bbox, ebnd, egid, eloc, e0, e1, np.array([[0, 1, 0]], np.int64),
                              0.0, False, W, out) == 0


def _boxes(centres, half):
    c = np.asarray(centres, float)
    return np.column_stack([c[:, 0] - half, c[:, 1] - half, c[:, 0] + half, c[:, 1] + half])


def test_grain_pairs_meet_across_the_seam_once_or_at_both_images():
    # Grains near the left and the right side of a box 5 cells wide: with periodic x they are
    # a pair, the second met one period to the left of the first (or right, from the other
    # side); without, none. A grain that drifted whole periods out still meets the other at
    # its nearest image. In a box where two grains span the width, both images are pairs.
    grid = CellGrid((0.0, 0.0, 5.0, 3.0), 1.0, periodic_x=True)
    owned = np.ones(2, np.int8)
    for centres, k in (([[0.3, 1.5], [4.8, 1.5]], -1), ([[4.8, 1.5], [0.3, 1.5]], 1),
                       ([[0.3, 1.5], [4.8 + 5.0, 1.5]], -2), ([[0.3 - 10.0, 1.5], [4.8, 1.5]],
                                                            -3)):
        box = _boxes(centres, 0.3)
        cells = grid.cell_of(np.asarray(centres))
        got = grain_pairs(cells, owned, box, grid.nx, grid.ny, 0.1, 1, grid.period)
        assert got.tolist() == [[0, 1, k]]
        assert grain_pairs(cells, owned, box, grid.nx, grid.ny, 0.1, 1, 0.0).shape[0] == 0
    narrow = CellGrid((0.0, 0.0, 3.0, 3.0), 1.0, periodic_x=True)
    centres = np.array([[0.75, 1.5], [2.25, 1.5]])
    got = grain_pairs(narrow.cell_of(centres), owned, _boxes(centres, 0.75), 3, 3, 0.1, 2,
                      narrow.period)
    assert sorted(got.tolist()) == [[0, 1, -1], [0, 1, 0]]


def test_cell_grid_wraps_columns_in_x_only():
    g = CellGrid((0.0, 0.0, 4.0, 2.0), 1.0, periodic_x=True)
    pts = np.array([[-0.5, 0.5], [4.5, 1.5], [9.2, -3.0], [2.5, 7.0]])
    assert g.cell_of(pts).tolist() == [3, 4, 1, 6]
    assert g.period == 4.0 and CellGrid((0.0, 0.0, 4.0, 2.0), 1.0).period == 0.0


def test_tied_block_columns_move_as_one_and_book_their_own_energy():
    # A 3 x 1 block with its side columns tied: unequal forces on the left and right nodes give
    # both the velocity of their summed force over their summed mass; each node books its own
    # kinetic energy, and the total is that of the pair moving as one
    _, _, _, sets = block_mesh(0.0, 0.0, 3.0, 1.0, 3, 1)
    partner = tied_nodes([sets], np.array([0]), 8)
    assert partner.tolist() == [3, -1, -1, 0, 7, -1, -1, 4]
    rng = np.random.default_rng(4)
    m = rng.uniform(1.0, 2.0, 8)
    f = rng.normal(0.0, 1.0, (8, 2))
    v = np.tile(rng.normal(0.0, 1.0, 2), (8, 1))
    v[[0, 3]] = [0.3, -0.2]
    v[[4, 7]] = [-0.1, 0.5]
    v0 = v.copy()
    kin, acc = np.zeros(1), np.zeros((1, NACC))
    none = np.zeros((8, 2), np.int8)
    advance_velocities(v, f, m, none, np.zeros((8, 2)), 0.0, 1e-3, 8, np.zeros(8, np.int64),
                       acc, kin, False, np.zeros((0, 2)), partner)
    for i, p in ((0, 3), (4, 7)):
        assert v[i].tobytes() == v[p].tobytes()
        assert np.allclose(v[i], v0[i] + 1e-3 * (f[i] + f[p]) / (m[i] + m[p]), rtol=1e-14)
    free = [1, 2, 5, 6]
    assert np.allclose(v[free], v0[free] + 1e-3 * f[free] / m[free, None], rtol=1e-14)
    assert np.isclose(kin[0], 0.5 * np.sum(m[:, None] * v0 * v), rtol=1e-14)
    # The contacts see the pair's joint mass
    mj = joint_masses(m, partner)
    assert mj[0] == mj[3] == m[0] + m[3] and mj[[1, 2, 5, 6]].tolist() == m[[1, 2, 5, 6]].tolist()
    assert joint_masses(m, np.zeros(0, np.int64)) is m


def test_tied_block_columns_keep_one_temperature_and_the_pair_s_heat():
    # Unequal conducted heat and sources on the two tied columns: both take the increment of
    # the summed heat over the summed capacity (one temperature), the thermal energy gained is
    # exactly the heat given, and free nodes are updated as without ties (bit for bit)
    from pdfem.kernels.heat import advance_temperature

    _, _, _, sets = block_mesh(0.0, 0.0, 3.0, 1.0, 3, 1)
    partner = tied_nodes([sets], np.array([0]), 8)
    rng = np.random.default_rng(5)
    cap = rng.uniform(1.0, 2.0, 8)
    q, src = rng.normal(0.0, 1.0, 8), rng.normal(0.0, 1.0e-3, 8)
    temp = np.full(8, 300.0)
    heat = 1e-3 * q.sum() + src.sum()
    plain = temp.copy()
    advance_temperature(plain, q.copy(), src.copy(), cap, 1e-3, 8, np.zeros(0, np.int64))
    qq, ss = q.copy(), src.copy()
    advance_temperature(temp, qq, ss, cap, 1e-3, 8, partner)
    assert not qq.any() and not ss.any()
    for i, p in ((0, 3), (4, 7)):
        assert temp[i] == temp[p]
        want = 300.0 + (1e-3 * (q[i] + q[p]) + src[i] + src[p]) / (cap[i] + cap[p])
        assert np.isclose(temp[i], want, rtol=1e-15, atol=0.0)
    free = [1, 2, 5, 6]
    assert temp[free].tobytes() == plain[free].tobytes()
    assert np.isclose(np.sum(cap * (temp - 300.0)), heat, rtol=1e-12)


def test_prepared_grains_are_written_as_their_images_in_the_box():
    from pdfem.prepare.phases import wrap_into_box

    nodes = np.array([[[-0.3, 0.0], [0.1, 0.0]], [[2.9, 1.0], [3.3, 1.0]],
                      [[7.0, 2.0], [7.4, 2.0]], [[1.0, 0.0], [1.2, 0.0]]])
    wrap_into_box(nodes, (0.0, 0.0, 3.0, 5.0))
    assert np.allclose(nodes[:, :, 0], [[2.7, 3.1], [-0.1, 0.3], [1.0, 1.4], [1.0, 1.2]])


def test_an_element_pair_met_at_two_shifts_is_counted():
    # Key-sorted candidates: the pair (3, 7) at shifts 0 and 1 (an element half the box wide)
    # is one repeat; the same element with other partners and a wall are not
    from pdfem.effects.contact_candidates import repeated_pairs

    cand = np.array([[3, 5, 0], [3, 7, 0], [3, 7, 1], [3, -1, 0], [4, 7, -1]], np.int64)
    assert repeated_pairs(cand) == 1
    assert repeated_pairs(np.delete(cand, 2, axis=0)) == 0
