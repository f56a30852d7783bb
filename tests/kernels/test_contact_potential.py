"""The potential contact law: W and its exact gradient, closed forms, and an element pushed
wholly into another (or behind a wall) still repelled."""

import numpy as np
import pytest

from pdfem.kernels import contact as C
from pdfem.kernels import contact_law as L
from pdfem.kernels import contact_potential as P
from pdfem.kernels.overlap import alloc_clip_buffers
from tests.kernels.contact_helpers import SQ, random_quad
from tests.kernels.test_contact import law_params, outputs, run_pairs, two_elements

KN0 = 1e9
# Corner values of an element that is a body of its own
ZERO4 = np.zeros(4)
DMAX = 0.5


def buffers():
    return (*alloc_clip_buffers(), np.empty((3, 2)), np.empty((8, 2)))


def pair_w(x, ha, hb):
    px, py, pt, tri, g = buffers()
    return P.pair_potential(x[:4], x[4:], ZERO4, ha, ZERO4, hb, px, py, pt, tri, g), g


def wall_w(xa, ha, p0, n):
    px, py, pt, tri, g = buffers()
    return P.wall_potential(xa, ha, p0[0], p0[1], n[0], n[1], px, py, pt, tri, g), g


def fd_gradient(fun, x, eps=1e-7):
    """Central differences of fun at x, every coordinate."""
    out = np.zeros_like(x)
    for i in np.ndindex(*x.shape):
        xp = x.copy()
        xm = x.copy()
        xp[i] += eps
        xm[i] -= eps
        out[i] = (fun(xp) - fun(xm)) / (2 * eps)
    return out


def test_pair_gradient_is_exact_for_random_quads():
    rng = np.random.default_rng(11)
    checked = 0
    while checked < 40:
        x = np.vstack([random_quad(rng, spread=0.3), random_quad(rng, spread=0.3)])
        w, g = pair_w(x, 0.55, 0.45)
        if w <= 1e-6:
            continue
        fd = fd_gradient(lambda y: pair_w(y, 0.55, 0.45)[0], x)
        # Measured below 1e-8 of the largest component (the differences' own error)
        assert np.abs(fd - g).max() <= 1e-6 * np.abs(g).max()
        # W is invariant under translation: the gradient sums to zero
        assert np.abs(g.sum(0)).max() <= 1e-13 * np.abs(g).max()
        checked += 1


def test_pair_gradient_nonconvex_host():
    # B has a reflex corner at node 2, its four triangles still positive
    xb = np.array([[0.0, 0.0], [1.0, 0.0], [0.55, 0.45], [0.0, 1.0]]) + [0.3, 0.1]
    xa = SQ * 0.5 + [0.4, 0.2]
    x = np.vstack([xa, xb])
    w, g = pair_w(x, 0.25, 0.5)
    assert w > 0
    fd = fd_gradient(lambda y: pair_w(y, 0.25, 0.5)[0], x)
    assert np.abs(fd - g).max() <= 1e-6 * np.abs(g).max()


# A host whose reflex corner (node 1) lies beyond its centroid, so that its triangle 1 holds no
# potential: the shape of an element of the 1-point rule at 1500 m/s (scaled from micrometres)
FOLDED = np.array([[653.0, 1880.0], [713.0, 1826.0], [725.0, 1784.0], [724.0, 1871.0]])
TOUCHING = np.array([[685.0, 1787.0], [711.0, 1766.0], [720.0, 1778.0], [722.0, 1816.0]])


def test_folded_host_triangle_holds_nothing_and_gradient_stays_exact():
    tri = np.empty((3, 2))
    assert P.folded_triangles(FOLDED, tri) == 0b0010
    x = np.vstack([TOUCHING, FOLDED]) * 1e-2
    w, g = pair_w(x, 0.174, 0.213)
    assert w > 0
    fd = fd_gradient(lambda y: pair_w(y, 0.174, 0.213)[0], x, eps=1e-6)
    # Without the inner edges' terms B's rows were off by 1.75 times the largest component
    assert np.abs(fd - g).max() <= 1e-6 * np.abs(g).max()
    assert np.abs(g.sum(0)).max() <= 1e-12 * np.abs(g).max()


def test_folded_element_behind_wall_gradient_stays_exact():
    xa = FOLDED * 1e-2
    for y0 in (18.3, 18.6, 18.0):
        w, g = wall_w(xa, 0.213, (0.0, y0), (0.0, 1.0))
        assert w > 0
        fd = fd_gradient(lambda y, y0=y0: wall_w(y, 0.213, (0.0, y0), (0.0, 1.0))[0], xa,
                         eps=1e-6)
        assert np.abs(fd - g[:4]).max() <= 1e-6 * np.abs(g[:4]).max()


def test_random_hosts_with_folded_triangles():
    # Quads with one corner pulled past the centroid, against random quads
    rng = np.random.default_rng(21)
    tri = np.empty((3, 2))
    checked = 0
    while checked < 30:
        xb = random_quad(rng, spread=0.3)
        k = rng.integers(4)
        c = xb.mean(0)
        xb[k] = c + rng.uniform(0.2, 1.2) * (c - xb[k]) * 0.5
        if P.folded_triangles(xb, tri) == 0 or P.folded_triangles(xb, tri) == 15:
            continue
        x = np.vstack([random_quad(rng, spread=0.3) + rng.normal(0, 0.2, 2), xb])
        w, g = pair_w(x, 0.4, 0.5)
        if w <= 1e-4:
            continue
        fd = fd_gradient(lambda y: pair_w(y, 0.4, 0.5)[0], x)
        assert np.abs(fd - g).max() <= 1e-6 * np.abs(g).max()
        checked += 1


def test_flat_contact_closed_form():
    # Two squares of side s over a whole edge by d: W = s d^2 - 2 d^3 / 3 (each square's
    # potential is its distance to the nearest edge)
    s = 2.0
    for d in (1e-3, 0.05, 0.3):
        x = np.vstack([SQ * s, SQ * s + [s - d, 0.0]])
        w, g = pair_w(x, s / 2, s / 2)
        assert w == pytest.approx(s * d * d - 2 * d ** 3 / 3, rel=1e-12)
        # dW/dd for a translation of A: 2 s d - 2 d^2
        assert g[:4, 0].sum() == pytest.approx(2 * s * d - 2 * d * d, rel=1e-12)


def test_wall_gradient_and_closed_form():
    rng = np.random.default_rng(5)
    for _ in range(20):
        xa = random_quad(rng, spread=0.2)
        n = np.array([np.cos(a := rng.uniform(0, 2 * np.pi)), np.sin(a)])
        p0 = rng.normal(0, 0.2, 2)
        w, g = wall_w(xa, 0.5, p0, n)
        if w <= 1e-6:
            continue
        fd = fd_gradient(lambda y, p0=p0, n=n: wall_w(y, 0.5, p0, n)[0], xa)
        assert np.abs(fd - g[:4]).max() <= 1e-6 * np.abs(g[:4]).max()
    # A unit square wholly behind the floor y = 0 with its top at depth D: W = 1/6 + D + 1/2
    # (its pyramid of volume 1/6, and the mean depth D + 1/2); dW/dy = -1 for the square
    w, g = wall_w(SQ - [0.0, 1.0 + 0.3], 0.5, (0.0, 0.0), (0.0, 1.0))
    assert w == pytest.approx(1 / 6 + 0.3 + 0.5, rel=1e-14)
    assert g[:4].sum(0) == pytest.approx([0.0, -1.0], abs=1e-14)


def energy_and_forces(x, conn, ebnd, egid, eloc, elen, law):
    """Normal energy and nodal forces of the single pair (0, 1), frictionless, no shear."""
    par = law_params(1, kn0=KN0, dmax=DMAX, ks=0.0, mu=0.0, law=law)
    _, out = run_pairs(x, np.zeros_like(x), conn, ebnd, egid, eloc, elen,
                       np.array([[0, 1]], np.int64), par, np.zeros(1))
    return out


def pair_energy(x, conn, ebnd, egid, eloc, elen):
    """The pair's stored energy under the potential law."""
    return energy_and_forces(x, conn, ebnd, egid, eloc, elen, L.LAW_POTENTIAL)[5][0, C.R_ENERGY]


def test_element_wholly_inside_another_is_repelled():
    # A small square B (side b) wholly inside the host A (side s = 1), in A's right triangle
    # at distance u of B's centre from A's right edge: W = b^2 u + b^3 / 6, dW/dx_B = -b^2
    b, u = 0.1, 0.2
    xa = SQ.copy()
    xb = SQ * b + [1.0 - u - b / 2, 0.5 - b / 2]
    x, conn, ebnd, egid, eloc, elen = two_elements(xa, xb)
    out = energy_and_forces(x, conn, ebnd, egid, eloc, elen, L.LAW_POTENTIAL)
    act, nodes, _, fnod, _, res = out
    assert act[0] == C.C_ACTIVE
    ln = min(elen)
    w = b * b * u + b ** 3 / 6
    delta = np.sqrt(w / ln)
    assert res[0, C.R_DELTA] == pytest.approx(delta, rel=1e-12)
    tn = -L.normal_force(delta, 1.0, KN0, DMAX, 0.95)[0]
    # The force on B points out through A's nearest edge (+x) with magnitude t_n b^2 / (2 delta)
    fb = fnod[0, 4:].sum(0)
    assert fb[0] == pytest.approx(tn * b * b / (2 * delta), rel=1e-12)
    assert abs(fb[1]) <= 1e-12 * fb[0]
    # ... and is minus the gradient of the contact's energy, node by node
    fd = fd_gradient(lambda y: pair_energy(y, conn, ebnd, egid, eloc, elen), x, eps=1e-8)
    f = np.zeros_like(x)
    f[nodes[0]] += fnod[0]
    assert np.abs(f + fd).max() <= 1e-6 * np.abs(f).max()
    # The report's area law has no force to give here: the pair is a guard
    act_area = energy_and_forces(x, conn, ebnd, egid, eloc, elen, L.LAW_AREA)[0]
    assert act_area[0] == C.C_INSIDE


def test_deeper_inside_is_pushed_harder():
    # Pushing B from A's edge towards its centre: W and the outward force both grow
    xa = SQ.copy()
    last_w, last_f = 0.0, 0.0
    for u in (0.0, 0.1, 0.2, 0.3, 0.4):
        xb = SQ * 0.1 + [1.0 - u - 0.05, 0.45]
        x, conn, ebnd, egid, eloc, elen = two_elements(xa, xb)
        act, _, _, fnod, _, res = energy_and_forces(x, conn, ebnd, egid, eloc, elen,
                                                    L.LAW_POTENTIAL)
        assert act[0] == C.C_ACTIVE
        fb = fnod[0, 4:].sum(0)[0]
        assert res[0, C.R_ENERGY] > last_w and fb > last_f > -1.0
        last_w, last_f = res[0, C.R_ENERGY], fb


def test_random_pairs_forces_are_energy_gradient():
    rng = np.random.default_rng(8)
    done = 0
    while done < 10:
        xa, xb = random_quad(rng, spread=0.3), random_quad(rng, spread=0.3)
        x, conn, ebnd, egid, eloc, elen = two_elements(xa, xb)
        act, nodes, _, fnod, _, res = energy_and_forces(x, conn, ebnd, egid, eloc, elen,
                                                        L.LAW_POTENTIAL)
        if act[0] != C.C_ACTIVE or res[0, C.R_DELTA] < 1e-3:
            continue

        f = np.zeros_like(x)
        f[nodes[0]] += fnod[0]
        fd = fd_gradient(lambda y, mesh=(conn, ebnd, egid, eloc, elen): pair_energy(y, *mesh),
                         x, eps=1e-8)
        assert np.abs(f + fd).max() <= 1e-5 * np.abs(f).max()
        assert np.abs(f.sum(0)).max() <= 1e-12 * np.abs(f).max()
        done += 1


def test_flat_contact_matches_area_law_to_leading_order():
    s, d = 1.0, 1e-3
    x, conn, ebnd, egid, eloc, elen = two_elements(SQ * s, SQ * s + [s - d, 0.0])
    res_p = energy_and_forces(x, conn, ebnd, egid, eloc, elen, L.LAW_POTENTIAL)[5]
    res_a = energy_and_forces(x, conn, ebnd, egid, eloc, elen, L.LAW_AREA)[5]
    # delta = d sqrt(1 - 2 d / 3 s) against d
    assert res_p[0, C.R_DELTA] == pytest.approx(d * np.sqrt(1 - 2 * d / (3 * s)), rel=1e-12)
    assert res_a[0, C.R_DELTA] == pytest.approx(d, rel=1e-12)
    assert res_p[0, C.R_FN] == pytest.approx(res_a[0, C.R_FN], rel=2 * d)
    assert res_p[0, C.R_NX] == pytest.approx(1.0) and res_p[0, C.R_WIDTH] == pytest.approx(s)


def test_element_behind_wall_is_repelled():
    # A unit square wholly behind the floor y = 0 (its top at depth 0.3)
    xa = SQ - [0.0, 1.3]
    conn = np.array([[0, 1, 2, 3]], np.int64)
    ebnd = np.ones((1, 4), np.int8)
    elen = np.array([1.0])
    out = outputs(1)
    for law, code in ((L.LAW_POTENTIAL, C.C_ACTIVE), (L.LAW_AREA, C.C_INSIDE)):
        par = law_params(1, kn0=KN0, dmax=5.0, ks=0.0, mu=0.0, law=law)
        C.element_wall_forces(xa, np.zeros_like(xa), conn, ebnd, elen, np.zeros(1, np.int64),
                              np.zeros((1, 2)), np.array([[0.0, 1.0]]), par, np.zeros(1),
                              *out, np.ones(4), 0.0)
        assert out[0][0] == code
    res = out[5]
    # W = 1/6 + 0.8 behind the floor: the force is t_n dW/dy / (2 delta) along +y
    par = law_params(1, kn0=KN0, dmax=5.0, ks=0.0, mu=0.0, law=L.LAW_POTENTIAL)
    C.element_wall_forces(xa, np.zeros_like(xa), conn, ebnd, elen, np.zeros(1, np.int64),
                          np.zeros((1, 2)), np.array([[0.0, 1.0]]), par, np.zeros(1), *out,
                          np.ones(4), 0.0)
    delta = np.sqrt(1 / 6 + 0.8)
    tn = -L.normal_force(delta, 1.0, KN0, 5.0, 0.95)[0]
    assert res[0, C.R_DELTA] == pytest.approx(delta, rel=1e-13)
    assert out[3][0, :4].sum(0) == pytest.approx([0.0, tn / (2 * delta)], rel=1e-12)
    assert res[0, C.R_NY] == pytest.approx(-1.0)


def test_rounding_level_potential_is_no_contact():
    # Two slivers along a wall, each crossing itself, from a 1-point run at 2000 m/s: W is
    # 4e-46 m^3 with a zero gradient, which has no normal; like a rounding-level area under the
    # area law it is no contact, not a guard
    x = np.array([[2.5586358897955492e-05, 1.2077436720927353e-03],
                  [7.7062524796725978e-06, 1.2319582590957295e-03],
                  [-2.3030245597191520e-07, 1.5443847125299695e-03],
                  [-4.3489920896447433e-07, 1.2183661758106477e-03],
                  [1.4908176001314819e-04, 1.4645629909709780e-03],
                  [1.7746642397814985e-06, 1.4862623718779455e-03],
                  [4.1180737978543913e-06, 1.4465940065746736e-03],
                  [1.2702795741570462e-04, 1.4790894768992864e-03]])
    elen = np.array([3.7387045623255844e-05, 3.2725218946895976e-05])
    w, g = pair_w(x, elen[0] / 2, elen[1] / 2)
    assert 0.0 < w < 1e-40 and not np.any(g[:4].sum(0))
    _, conn, _, egid, eloc, _ = two_elements(x[:4], x[4:])
    ebnd = np.array([[0, 1, 1, 0], [0, 1, 0, 0]], np.int8)
    act = energy_and_forces(x, conn, ebnd, egid, eloc, elen, L.LAW_POTENTIAL)[0]
    assert act[0] == C.C_NONE


# ---- the body's potential: corner values, and a grain pushed into another's inside ----


def test_pair_gradient_is_exact_with_corner_values():
    # Potentials that hold values at the corners (a body's depth field, grain_depth): the
    # host's outer edges then carry the field, and their sweep is part of the gradient
    rng = np.random.default_rng(31)
    px, py, pt, tri, g = buffers()
    checked = 0
    while checked < 40:
        x = np.vstack([random_quad(rng, spread=0.3), random_quad(rng, spread=0.3)])
        da, db = rng.uniform(0.0, 1.0, 4), rng.uniform(0.0, 1.0, 4)
        da[rng.integers(4)] = 0.0
        ca, cb = 0.25 * da.sum() + 0.1, 0.25 * db.sum()

        def w_of(y, da=da, db=db, ca=ca, cb=cb):
            return P.pair_potential(y[:4], y[4:], da, ca, db, cb, px, py, pt, tri, g)

        w = w_of(x)
        if w <= 1e-6:
            continue
        grad = g.copy()
        fd = fd_gradient(w_of, x)
        assert np.abs(fd - grad).max() <= 1e-6 * np.abs(grad).max()
        assert np.abs(grad.sum(0)).max() <= 1e-12 * np.abs(grad).max()
        checked += 1


def grid_grain(n, side=1.0):
    """A square grain of n x n unit quads (CCW), its boundary flags and contact lengths."""
    from pdfem.build import boundary_flags, contact_lengths

    i, j = np.meshgrid(np.arange(n + 1), np.arange(n + 1), indexing="ij")
    x = side * np.stack([i.ravel(), j.ravel()], axis=1).astype(float)
    nid = np.arange((n + 1) ** 2).reshape(n + 1, n + 1)
    conn = np.array([[nid[a, b], nid[a + 1, b], nid[a + 1, b + 1], nid[a, b + 1]]
                     for a in range(n) for b in range(n)], np.int64)
    ebnd = boundary_flags(conn)
    return x, conn, ebnd, contact_lengths(x, conn, ebnd)


def test_grain_depth_layers_of_a_square_grain():
    from pdfem.kernels.grain_depth import element_depths

    x, conn, ebnd, elen = grid_grain(3)
    edep, eapex = np.full((9, 4), -1.0), np.full(9, -1.0)
    element_depths(conn, ebnd, elen, np.array([0]), np.array([9]), np.array([0]),
                   np.array([16]), edep, eapex)
    # The 12 boundary nodes at depth 0, the 4 inner ones one layer (the unit elen = 1) in
    inner = np.all((x > 0.5) & (x < 2.5), axis=1)
    depth = np.zeros(16)
    depth[inner] = 1.0
    assert np.array_equal(edep, depth[conn])
    # Centroids: half an element below the shallowest corner (the centre element: 1.5, its
    # centroid's distance to the boundary) or the corners' mean, whichever is larger
    centre = int(np.flatnonzero(np.all(ebnd == 0, axis=1))[0])
    assert eapex[centre] == 1.5
    assert np.all(eapex[np.arange(9) != centre] == 0.5)


def grain_and_square(dy, depth):
    """A 3 x 3 grain (body 0, side 1) and a square of side 0.4 (body 1) whose lower edge lies
    dy below the grain's top, over the middle column; the contact of every element of the
    grain with the square: (total energy, force on the square, active codes)."""
    from pdfem.kernels.grain_depth import element_depths

    xg, cg, eg, lg = grid_grain(3)
    xs = SQ * 0.4 + [1.3, 3.0 - dy]
    x = np.vstack([xg, xs])
    conn = np.vstack([cg, [[16, 17, 18, 19]]]).astype(np.int64)
    ebnd = np.vstack([eg, [[1, 1, 1, 1]]]).astype(np.int8)
    elen = np.r_[lg, 0.4]
    egid = np.r_[np.zeros(9, np.int64), 1]
    eloc = np.r_[np.arange(9), 0].astype(np.int64)
    edep, eapex = np.zeros((10, 4)), 0.5 * elen
    if depth:
        element_depths(conn, ebnd, elen, np.array([0, 9]), np.array([9, 1]),
                       np.array([0, 16]), np.array([16, 4]), edep, eapex)
    pairs = np.array([[e, 9] for e in range(9)], np.int64)
    out = outputs(9)
    C.element_pair_forces(x, np.zeros_like(x), conn, ebnd, egid, eloc, elen, pairs,
                          law_params(9, kn0=KN0, dmax=10.0, law=L.LAW_POTENTIAL), np.zeros(9),
                          *out, np.ones(len(x)), 0.0, depth=(edep, eapex))
    act, _, _, fnod, _, res = out
    return res[:, C.R_ENERGY].sum(), fnod[:, 4:].sum(axis=(0, 1)), act


def test_grain_pushed_into_another_is_repelled_at_every_depth():
    # The square pushed down through the grain's top boundary element into its centre element
    # and on towards the grain's middle (y = 1.5): the energy rises all the way, the force on
    # the square points back out (+y) and is the energy's gradient (central differences)
    last = 0.0
    for dy in (0.1, 0.5, 0.9, 1.2, 1.45, 1.6):
        e, f, act = grain_and_square(dy, True)
        assert e > last
        assert f[1] > 0.0 and abs(f[0]) <= 1e-9 * f[1]
        h = 1e-7
        de = (grain_and_square(dy + h, True)[0] - grain_and_square(dy - h, True)[0]) / (2 * h)
        assert f[1] == pytest.approx(de, rel=1e-6)
        last = e
        if dy == 1.45:
            # Wholly inside the grain's centre element: its pair is one of the contacts
            assert act[4] == C.C_ACTIVE
    # Centred on the grain's middle it is pushed nowhere; past it, out through the nearer side
    e, f, _ = grain_and_square(1.7, True)
    assert e > last and abs(f[1]) <= 1e-12 * last
    assert grain_and_square(2.0, True)[1][1] < 0.0
    # With each element's own potential (zero on its edges, none in an element without a
    # contact length), the square inside the centre element is pushed nowhere
    e, f, _ = grain_and_square(1.45, False)
    assert e == 0.0 and not f.any()
