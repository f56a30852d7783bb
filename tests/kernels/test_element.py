"""Element kernels: patch test, rigid spin objectivity, mass, energy, numpy twin, dt, quality."""

import numpy as np
import pytest

from pdfem.kernels.elastic import elastic_energy_density, elastic_update
from pdfem.kernels.element import q4_forces_2x2
from pdfem.kernels.element_1pt import (
    HG_BENDING,
    HG_COEFFICIENT,
    HG_COLS,
    HG_COLS_POINTS,
    HG_FULL,
    HG_POINTS,
    hourglass_reference,
    q4_forces_1pt,
)
from pdfem.kernels.element_measures import q4_lumped_mass, q4_strain_energy
from pdfem.kernels.params import BULK, CAP, ELASTIC, MODEL, NPAR, RHO, SHEAR
from pdfem.kernels.stable import q4_stable_dt
from pdfem.mesh.quality import jacobian_ratio
from pdfem.tools.bench.numpy_element import hourglass_reference as numpy_hourglass_reference
from pdfem.tools.bench.numpy_element import numpy_forces_1pt, numpy_forces_2x2

K = 1.0e10
G = 6.0e9
RHO0 = 2500.0
E = 9.0 * K * G / (3.0 * K + G)
HGC = 0.1
RULES = {"1pt": (q4_forces_1pt, numpy_forces_1pt, 1), "2x2": (q4_forces_2x2, numpy_forces_2x2, 4)}


UNKNOWN_MODEL = 7.0


def material(model=ELASTIC):
    """One-row material table."""
    mat = np.zeros((1, NPAR))
    mat[0, [MODEL, RHO, BULK, SHEAR]] = [model, RHO0, K, G]
    return mat


def grid(nx, ny, jitter, seed, offset=(0.0, 0.0)):
    """Jittered nx x ny grid of unit quads (all nodes moved), counter-clockwise connectivity."""
    rng = np.random.default_rng(seed)
    gx, gy = np.meshgrid(np.arange(nx + 1.0), np.arange(ny + 1.0), indexing="xy")
    x = np.stack([gx.ravel(), gy.ravel()], axis=1)
    x += rng.uniform(-jitter, jitter, size=x.shape) + np.asarray(offset)
    i, j = np.meshgrid(np.arange(nx), np.arange(ny), indexing="xy")
    n0 = (j * (nx + 1) + i).ravel()
    conn = np.stack([n0, n0 + 1, n0 + nx + 2, n0 + nx + 1], axis=1).astype(np.int64)
    return x, conn


def reference(xref, conn, coef=HGC, cols=HG_COLS):
    """The 1-point rule's hourglass reference of the configuration xref (pdfem.kernels)."""
    hg = np.zeros((conn.shape[0], cols))
    hourglass_reference(xref, conn, coef, 0, conn.shape[0], hg)
    return hg


class State:
    """Per-element arrays of one run; the 1-point rule's hourglass reference is xref's (no
    hourglass control without it), its spring the coefficient's (HGC) or the bending one."""

    def __init__(self, nn, ne, nip, xref=None, conn=None, model=HG_COEFFICIENT):
        self.sig = np.zeros((ne, nip, 4))
        self.mstate = np.zeros((ne, nip, 0))
        self.model = model
        coef = HGC if model == HG_COEFFICIENT else 1.0
        cols = HG_COLS_POINTS if model == HG_POINTS else HG_COLS
        self.hg = (reference(xref, conn, coef, cols) if nip == 1 and xref is not None
                   else np.zeros((0, HG_COLS)))
        self.f = np.zeros((nn, 2))
        self.ewint = np.zeros(ne)
        self.ewp = np.zeros(ne)

    def step(self, fn, x, du, conn, mat, e0=0, e1=None):
        """One force evaluation; f is cleared first."""
        e1 = conn.shape[0] if e1 is None else e1
        self.f[:] = 0.0
        emat = np.zeros(conn.shape[0], dtype=np.int32)
        return fn(x, du, conn, emat, mat, self.sig, self.mstate, self.hg, self.model, e0, e1,
                  self.f, self.ewint, self.ewp, np.zeros((0, 3)))


def c_apply(deps):
    """C:deps for (xx, yy, xy, zz) tensor components."""
    lam = K - 2.0 * G / 3.0
    tr = deps[0] + deps[1] + deps[3]
    return np.array([lam * tr + 2 * G * deps[0], lam * tr + 2 * G * deps[1], 2 * G * deps[2],
                     lam * tr + 2 * G * deps[3]])


@pytest.mark.parametrize("rule", ["1pt", "2x2"])
def test_patch_linear_increment(rule):
    """du = H X (+ translation) from a uniform stress: uniform closed-form stress, no residual."""
    fn, _, nip = RULES[rule]
    xref, conn = grid(3, 3, 0.15, seed=1, offset=(10.0, -4.0))
    h = np.array([[1.0e-3, 2.0e-3], [-1.5e-3, -0.5e-3]])
    du = xref @ h.T + np.array([3e-4, -2e-4])
    x = xref + du
    st = State(x.shape[0], conn.shape[0], nip, xref, conn)
    sig0 = np.array([1.0e6, -2.0e6, 5.0e5, 3.0e5])
    st.sig[:] = sig0
    assert st.step(fn, x, du, conn, material()) == -1
    # Closed form: L = H (I + H/2)^-1 at x_mid = (I + H/2) X + t/2, Cayley rotation, then C:deps
    lg = h @ np.linalg.inv(np.eye(2) + 0.5 * h)
    w = 0.5 * (lg - lg.T)
    q = np.linalg.solve(np.eye(2) - 0.5 * w, np.eye(2) + 0.5 * w)
    s2 = q @ np.array([[sig0[0], sig0[2]], [sig0[2], sig0[1]]]) @ q.T
    d = 0.5 * (lg + lg.T)
    expect = np.array([s2[0, 0], s2[1, 1], s2[0, 1], sig0[3]]) + c_apply(
        np.array([d[0, 0], d[1, 1], d[0, 1], 0.0]))
    scale = np.max(np.abs(expect))
    assert np.max(np.abs(st.sig - expect)) <= 1e-12 * scale
    # Interior nodes (5, 6, 9, 10 of the 4 x 4 grid) carry no net force (a linear field has no
    # hourglass mode)
    interior = [5, 6, 9, 10]
    fscale = np.max(np.abs(st.f))
    assert np.max(np.abs(st.f[interior])) <= 1e-12 * fscale


def grain6():
    """Six convex quads (3 x 2 jittered grid) centred near (5, 3)."""
    x, conn = grid(3, 2, 0.2, seed=7, offset=(3.5, 2.0))
    return x, conn


def rotate(xref, centre, theta):
    """Rigid rotation of points xref about centre by theta."""
    c, s = np.cos(theta), np.sin(theta)
    r = np.array([[c, -s], [s, c]])
    return centre + (xref - centre) @ r.T


@pytest.mark.parametrize("rule", ["1pt", "2x2"])
def test_rigid_spin_stress_free(rule):
    """360 degrees in 3600 prescribed steps: |stress| < 1e-9 * E * 1e-3 (strain scale 1e-3);
    no hourglass force and no work at any step."""
    fn, _, nip = RULES[rule]
    xref, conn = grain6()
    centre = np.array([5.0, 3.0])
    st = State(xref.shape[0], conn.shape[0], nip, xref, conn)
    mat = material()
    xold = xref.copy()
    for k in range(1, 3601):
        x = rotate(xref, centre, 2.0 * np.pi * k / 3600)
        assert st.step(fn, x, x - xold, conn, mat) == -1
        xold = x
    tol = 1e-9 * E * 1e-3
    assert np.max(np.abs(st.sig)) < tol
    assert np.max(np.abs(st.f)) < tol  # N/m over elements of size ~1 m
    assert np.max(np.abs(st.ewint)) < tol * 1e-3


@pytest.mark.parametrize("rule", ["1pt", "2x2"])
def test_prestressed_rotation_90(rule):
    """A uniform sigma_xx rotated rigidly by 90 degrees becomes sigma_yy; sigma_zz is kept."""
    fn, _, nip = RULES[rule]
    xref = np.array([[0.0, 0.0], [1.2, 0.1], [1.1, 0.9], [-0.1, 1.0]])
    conn = np.array([[0, 1, 2, 3]], dtype=np.int64)
    st = State(4, 1, nip)
    st.sig[:] = [2.0e6, 0.0, 0.0, 7.0e5]
    xold = xref.copy()
    for k in range(1, 91):
        x = rotate(xref, np.array([0.5, 0.5]), 0.5 * np.pi * k / 90)
        assert st.step(fn, x, x - xold, conn, material()) == -1
        xold = x
    np.testing.assert_allclose(st.sig[0], np.tile([0.0, 2.0e6, 0.0, 7.0e5], (nip, 1)),
                               rtol=0, atol=1e-6 * 2.0e6)


def bending_modulus(k, g):
    """E' of plane-strain bending from the continuum: a strain eps_xx with no shear and no
    stress across (eps_yy chosen so that sigma_yy = 0, eps_zz = 0) stores E' eps_xx^2 / 2."""
    lam = k - 2.0 * g / 3.0
    exx = 1.0
    eyy = -lam * exx / (lam + 2.0 * g)
    return c_apply(np.array([exx, eyy, 0.0, 0.0])) @ np.array([exx, eyy, 0.0, 0.0])


@pytest.mark.parametrize("model", [HG_COEFFICIENT, HG_BENDING, HG_FULL])
@pytest.mark.parametrize("d", [1e-5, 0.3])
def test_hourglass_mode_resisted(d, model):
    """Unit square, du = d h in x, small or large: no strain, the force -k d gamma with
    k = hg_coef (K + 4G/3) (B.B)/A, bending (2/3) E' (B.B)/A or full (2/3)(K + 7G/3) (B.B)/A,
    and gamma = h/4, and the work k d^2 / 2, exactly."""
    x0 = np.array([[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]])
    conn = np.array([[0, 1, 2, 3]], dtype=np.int64)
    h = np.array([1.0, -1.0, 1.0, -1.0])
    du = np.zeros((4, 2))
    du[:, 0] = d * h
    st = State(4, 1, 1, x0, conn, model)
    assert st.step(q4_forces_1pt, x0 + du, du, conn, material()) == -1
    # Centroid strain vanishes; B.B / A = A b.b = 2 for the unit square; q = d (gamma.h = 1)
    assert np.max(np.abs(st.sig)) == 0.0
    m = {HG_COEFFICIENT: HGC * (K + 4.0 * G / 3.0), HG_BENDING: 2.0 * bending_modulus(K, G) / 3.0,
         HG_FULL: 2.0 * (K + 7.0 * G / 3.0) / 3.0}[model]
    k = m * 2.0
    # q is a difference of the corners' positions: rounding at the element's size, 1
    np.testing.assert_allclose(st.f[:, 0], -k * d * h / 4.0, rtol=1e-14, atol=1e-15 * k)
    assert np.all(st.f[:, 1] == 0.0)
    np.testing.assert_allclose(st.ewint, [0.5 * k * d * d], rtol=1e-14, atol=1e-15 * k * d)


@pytest.mark.parametrize("a,b", [(0.5, 0.5), (1.5, 0.5)])
def test_points_stiffness_is_the_two_by_two_rules_per_mode(a, b):
    """The points stiffness stores in each hourglass mode of a rectangle what the 2 x 2 rule
    stores, to the first order in the mode's size (here 1e-6 of the element)."""
    x0 = np.array([[-a, -b], [a, -b], [a, b], [-a, b]])
    conn = np.array([[0, 1, 2, 3]], dtype=np.int64)
    h = np.array([1.0, -1.0, 1.0, -1.0])
    for axis in (0, 1):
        du = np.zeros((4, 2))
        du[:, axis] = 1e-6 * h
        work = []
        for rule, model in (("1pt", HG_POINTS), ("2x2", HG_COEFFICIENT)):
            fn, _, nip = RULES[rule]
            st = State(4, 1, nip, x0, conn, model)
            assert st.step(fn, x0 + du, du, conn, material()) == -1
            work.append(st.ewint[0])
        assert work[0] == pytest.approx(work[1], rel=1e-4)


def test_points_stiffness_stops_a_closing_corner():
    """A square whose corner 2 is pushed towards corner 0 along the diagonal, past the point
    where the element stops being convex (0.5): the points energy grows ever faster as the
    nearest point's Jacobian falls to zero (the coefficient spring's as the square of the
    push), and the kernel stops on the element once a point turns over."""
    x0 = np.array([[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]])
    conn = np.array([[0, 1, 2, 3]], dtype=np.int64)
    energies = {}
    for model in (HG_POINTS, HG_COEFFICIENT):
        st = State(4, 1, 1, x0, conn, model)
        out = []
        for s in (0.3, 0.5, 0.6):
            x = x0.copy()
            x[2] -= s
            e = np.zeros(1)
            q4_strain_energy(x, conn, np.zeros(1, np.int32), material(), np.zeros((1, 1, 4)),
                             st.hg, model, 0, 1, e)
            out.append(e[0])
        energies[model] = out
    pts, spring = energies[HG_POINTS], energies[HG_COEFFICIENT]
    assert all(b > a for a, b in zip(pts, pts[1:], strict=False))
    assert pts[-1] / pts[-2] > 2.0 * spring[-1] / spring[-2]
    # Past the turn-over of the point next to corner 2 the kernel stops on the element
    st = State(4, 1, 1, x0, conn, HG_POINTS)
    x = x0.copy()
    x[2] -= 0.7
    assert st.step(q4_forces_1pt, x, np.zeros_like(x), conn, material()) == 0


@pytest.mark.parametrize("a,b", [(0.5, 0.5), (1.5, 0.5)])
def test_full_stiffness_is_the_two_by_two_rules(a, b):
    """A rectangle 2a x 2b moved in its hourglass modes, in x and in y, from zero stress: the
    1-point rule's full stiffness stores in the two modes together what the 2 x 2 rule stores
    (each mode alone for a square), and for the x mode of the rectangle the 2 x 2 rule's
    closed form (4ab/3)(M/a^2 + G/b^2) d^2/2 (exact for a bilinear field)."""
    x0 = np.array([[-a, -b], [a, -b], [a, b], [-a, b]])
    conn = np.array([[0, 1, 2, 3]], dtype=np.int64)
    h = np.array([1.0, -1.0, 1.0, -1.0])
    d = 1e-6
    m = K + 4.0 * G / 3.0
    work = {}
    for rule, model in (("1pt", HG_FULL), ("2x2", HG_COEFFICIENT)):
        fn, _, nip = RULES[rule]
        for axis in (0, 1):
            du = np.zeros((4, 2))
            du[:, axis] = d * h
            st = State(4, 1, nip, x0, conn, model)
            assert st.step(fn, x0 + du, du, conn, material()) == -1
            work[rule, axis] = st.ewint[0]
    two = (4.0 * a * b / 3.0) * (m / a**2 + G / b**2) * d * d / 2.0
    assert work["2x2", 0] == pytest.approx(two, rel=1e-9)
    assert work["1pt", 0] + work["1pt", 1] == pytest.approx(work["2x2", 0] + work["2x2", 1],
                                                            rel=1e-9)
    if a == b:
        assert work["1pt", 0] == pytest.approx(work["2x2", 0], rel=1e-9)


@pytest.mark.parametrize("model", [HG_COEFFICIENT, HG_BENDING, HG_FULL, HG_POINTS])
@pytest.mark.parametrize("eos", [False, True])
def test_hourglass_force_is_the_gradient_of_its_energy(eos, model):
    """A jittered mesh drawn far from its reference (stretch, shear, rotation by 2 rad and a
    random non-affine part), compressed to 0.72 of its area: the kernel's hourglass forces
    equal minus the gradient of the stored hourglass energy by central differences, with a
    linear bulk and with the Hugoniot's bulk modulus stiffening the spring, and an affine map
    of the reference stores none."""
    from pdfem.kernels.params import EOS_S

    xref, conn = grid(3, 2, 0.25, seed=11)
    ne = conn.shape[0]
    mat = material()
    mat[0, EOS_S] = 2.29 if eos else 0.0
    st = State(xref.shape[0], ne, 1, xref, conn, model)
    c, s = np.cos(2.0), np.sin(2.0)
    affine = xref @ (np.array([[c, -s], [s, c]]) @ np.array([[1.2, 0.4], [0.0, 0.6]])).T + 3.0
    x = affine + np.random.default_rng(12).normal(scale=0.05, size=xref.shape)
    zero = np.zeros((ne, 1, 4))

    def energy(y):
        out = np.zeros(ne)
        q4_strain_energy(y, conn, np.zeros(ne, np.int32), mat, zero, st.hg, model, 0, ne,
                         out)
        return out.sum()

    # Zero stress and no increment: the kernel's force is the hourglass force alone
    st.sig[:] = 0.0
    st.step(q4_forces_1pt, x, np.zeros_like(x), conn, mat)
    st.sig[:] = 0.0
    grad = np.zeros_like(x)
    for i in range(x.shape[0]):
        for k in range(2):
            e = np.zeros_like(x)
            e[i, k] = 1e-6
            grad[i, k] = (energy(x + e) - energy(x - e)) / 2e-6
    np.testing.assert_allclose(st.f, -grad, rtol=0, atol=1e-6 * np.abs(grad).max())
    # The points energy of an affine map: H = I to rounding, Psi of order mu eps^2
    assert energy(affine) < (1e-14 if model == HG_POINTS else 1e-20) * energy(x)


@pytest.mark.parametrize("rule,model", [("1pt", HG_COEFFICIENT), ("1pt", HG_BENDING),
                                        ("1pt", HG_FULL), ("1pt", HG_POINTS),
                                        ("2x2", HG_COEFFICIENT)])
def test_first_step_work_equals_stored_energy(rule, model):
    """From zero stress, one step: ewint = stored energy (elastic + hourglass) exactly."""
    fn, _, nip = RULES[rule]
    xref, conn = grid(2, 2, 0.2, seed=3)
    du = np.random.default_rng(4).uniform(-1e-4, 1e-4, size=xref.shape)
    x = xref + du
    st = State(x.shape[0], conn.shape[0], nip, xref, conn, model)
    assert st.step(fn, x, du, conn, material()) == -1
    out = np.zeros(conn.shape[0])
    q4_strain_energy(x, conn, np.zeros(conn.shape[0], np.int32), material(), st.sig, st.hg,
                     model, 0, conn.shape[0], out)
    np.testing.assert_allclose(st.ewint, out, rtol=1e-12)
    assert np.all(out > 0.0) and np.all(st.ewp == 0.0)


def test_elastic_energy_density_closed_form():
    """0.5 sig:C^-1:sig equals 0.5 sig:eps for sig = C:eps, zz and shear included."""
    p = material()[0]
    eps = np.array([1e-4, -3e-4, 2e-4, 5e-5])
    sig = np.zeros(4)
    assert elastic_update(p, sig, eps, np.zeros(0)) == 0.0
    np.testing.assert_allclose(sig, c_apply(eps), rtol=1e-14)
    work = 0.5 * (sig[0] * eps[0] + sig[1] * eps[1] + 2 * sig[2] * eps[2] + sig[3] * eps[3])
    np.testing.assert_allclose(elastic_energy_density(p, sig), work, rtol=1e-12)


def test_lumped_mass_sums_to_rho_area():
    """Row-sum mass of a distorted patch sums to rho * area; a square gives rho A / 4 per node."""
    x, conn = grid(3, 3, 0.2, seed=2)
    ne = conn.shape[0]
    m = np.zeros(x.shape[0])
    q4_lumped_mass(x, conn, np.zeros(ne, np.int32), material(), 0, ne, m)
    xe = x[conn]
    area = 0.5 * np.sum(xe[:, :, 0] * np.roll(xe[:, :, 1], -1, axis=1)
                        - np.roll(xe[:, :, 0], -1, axis=1) * xe[:, :, 1])
    assert abs(m.sum() - RHO0 * area) <= 1e-14 * RHO0 * area
    sq = np.array([[0.0, 0.0], [2.0, 0.0], [2.0, 2.0], [0.0, 2.0]])
    m = np.zeros(4)
    q4_lumped_mass(sq, np.array([[0, 1, 2, 3]]), np.zeros(1, np.int32), material(), 0, 1, m)
    np.testing.assert_allclose(m, RHO0, rtol=1e-15)


@pytest.mark.parametrize("rule,model", [("1pt", HG_COEFFICIENT), ("1pt", HG_BENDING),
                                        ("2x2", HG_COEFFICIENT)])
def test_numba_matches_numpy(rule, model):
    """Several random steps on a distorted mesh, subrange included: twins agree to 1e-12."""
    fn, ref, nip = RULES[rule]
    xref, conn = grid(4, 3, 0.2, seed=5)
    runs = []
    for kernel in (fn, ref):
        rng = np.random.default_rng(6)
        st = State(xref.shape[0], conn.shape[0], nip, xref, conn, model)
        st.sig[:] = rng.normal(size=st.sig.shape) * 1e6
        if nip == 1:
            # The numpy twin's reference agrees with the kernel's
            twin = numpy_hourglass_reference(xref, conn, HGC if model == HG_COEFFICIENT else 1.0)
            assert np.max(np.abs(twin - st.hg)) <= 1e-15 * np.max(np.abs(st.hg))
        x = xref.copy()
        for _ in range(4):
            du = rng.uniform(-2e-3, 2e-3, size=x.shape)
            x = x + du
            assert st.step(kernel, x, du, conn, material(), 2, 10) == -1
        runs.append(st)
    a, b = runs
    for u, v in [(a.sig, b.sig), (a.f, b.f), (a.ewint, b.ewint)]:
        assert np.max(np.abs(u - v)) <= 1e-12 * np.max(np.abs(u))
    # Elements outside [2, 10) are untouched
    assert np.all(a.ewint[:2] == 0.0) and np.all(a.ewint[10:] == 0.0)


@pytest.mark.parametrize("rule", ["1pt", "2x2"])
def test_failures_return_element_index(rule):
    """An inverted element, or an unwired material model, is reported by its index."""
    fn, ref, nip = RULES[rule]
    x, conn = grid(3, 1, 0.0, seed=0)
    bad = x.copy()
    bad[7] = [1.5, -1.0]  # node 7 belongs to element 2 only: turns it inside out
    du = np.zeros_like(x)
    for kernel in (fn, ref):
        assert State(8, 3, nip).step(kernel, bad, du, conn, material()) == 2
        assert State(8, 3, nip).step(kernel, bad, du, conn, material(), 0, 2) == -1
    # A model id no kernel knows (the cap model is wired: see test_cap)
    st = State(8, 3, nip)
    assert st.step(fn, x, du, conn, material(UNKNOWN_MODEL)) == 0
    with pytest.raises(ValueError):
        State(8, 3, nip).step(ref, x, du, conn, material(CAP))


@pytest.mark.parametrize("rule", ["1pt", "2x2"])
def test_state_layouts_agree(rule):
    """mstate of shape (ne, nip, 0) and (0, nip, 0) give identical results."""
    fn, _, nip = RULES[rule]
    x, conn = grid(2, 2, 0.2, seed=8)
    du = np.random.default_rng(9).uniform(-1e-3, 1e-3, size=x.shape)
    a = State(x.shape[0], 4, nip)
    b = State(x.shape[0], 4, nip)
    b.mstate = np.zeros((0, nip, 0))
    a.step(fn, x + du, du, conn, material())
    b.step(fn, x + du, du, conn, material())
    assert np.array_equal(a.sig, b.sig) and np.array_equal(a.f, b.f)


def test_stable_dt_unit_square():
    """Unit square: L = area / longest diagonal = 1/sqrt(2); empty range gives +inf."""
    x = np.array([[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]])
    conn = np.array([[0, 1, 2, 3]], dtype=np.int64)
    emat = np.zeros(1, np.int32)
    cp = np.sqrt((K + 4.0 * G / 3.0) / RHO0)
    sig = np.zeros((1, 1, 4))
    np.testing.assert_allclose(q4_stable_dt(x, conn, emat, material(), sig, 0, 1),
                               1.0 / np.sqrt(2.0) / cp, rtol=1e-15)
    assert q4_stable_dt(x, conn, emat, material(), sig, 0, 0) == np.inf


def test_jacobian_ratio():
    """Square and sheared parallelogram: 1; corner (1,1) moved to (1+s,1): 1/(1+s)."""
    conn = np.array([[0, 1, 2, 3]] * 3, dtype=np.int64) + 4 * np.arange(3)[:, None]
    s = 0.4
    x = np.array([[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0],
                  [0.0, 0.0], [1.0, 0.0], [1.0 + s, 1.0], [s, 1.0],
                  [0.0, 0.0], [1.0, 0.0], [1.0 + s, 1.0], [0.0, 1.0]])
    np.testing.assert_allclose(jacobian_ratio(x, conn), [1.0, 1.0, 1.0 / (1.0 + s)], rtol=1e-15)


def test_one_point_kernel_is_the_material_point_under_uniform_strain():
    """A jittered mesh of cap and elastic elements in uniaxial strain, squeezed call after
    call until the cap points yield: each element's stress and cap state are those of its
    material point (material.material_update with the mid-step strain increment
    e / (1 + e/2)), to rounding; the kernel's inline cap trial and return are cap_update's."""
    from pdfem.kernels.cap import CAP_NST
    from pdfem.kernels.material import material_initial_state, material_update
    from pdfem.tools.bench.cap_yardstick import hmx_params

    x, conn = grid(16, 12, 0.2, 5)
    x = x * 1e-4
    ne = conn.shape[0]
    emat = (np.arange(ne) % 5 == 0).astype(np.int32)  # every fifth element elastic
    mat = np.concatenate([hmx_params(), material()])
    sig, mst = np.zeros((ne, 1, 4)), np.zeros((ne, 1, CAP_NST))
    material_initial_state(mst, emat, mat)
    hg, ew, ewp = reference(x, conn), np.zeros(ne), np.zeros(ne)
    # The two material points, one per row
    point = [(np.zeros(4), mst[np.nonzero(emat == m)[0][0], 0].copy()) for m in (0, 1)]
    ey = -4.0e-3
    for _ in range(12):
        du = np.stack([np.zeros(x.shape[0]), ey * x[:, 1]], axis=1)
        x = x + du
        f = np.zeros_like(x)
        assert q4_forces_1pt(x, du, conn, emat, mat, sig, mst, hg, HG_COEFFICIENT, 0, ne, f,
                             ew, ewp, np.zeros((0, 3))) == -1
        deps = np.array([0.0, ey / (1.0 + 0.5 * ey), 0.0, 0.0])
        for m, (s, st) in enumerate(point):
            status, _ = material_update(mat[m], s, deps, st)
            assert status == 0
    assert (ewp > 0).mean() > 0.5  # the cap points yielded
    for m, (s, st) in enumerate(point):
        rows = np.nonzero(emat == m)[0]
        scale = np.abs(s).max()
        np.testing.assert_allclose(sig[rows, 0], np.broadcast_to(s, (rows.size, 4)),
                                   rtol=1e-9, atol=1e-12 * scale)
        np.testing.assert_allclose(mst[rows, 0], np.broadcast_to(st, (rows.size, st.size)),
                                   rtol=1e-9, atol=1e-12 * max(np.abs(st).max(), 1.0))


def test_an_unknown_material_model_stops_the_one_point_kernel():
    x, conn = grid(4, 3, 0.2, 3)
    ne = conn.shape[0]
    emat = np.zeros(ne, np.int32)
    emat[5] = 1
    mat = np.concatenate([material(), material(UNKNOWN_MODEL)])
    du = np.full_like(x, 1e-4)
    bad = q4_forces_1pt(x + du, du, conn, emat, mat, np.zeros((ne, 1, 4)), np.zeros((ne, 1, 0)),
                        reference(x, conn), HG_COEFFICIENT, 0, ne, np.zeros_like(x), np.zeros(ne),
                        np.zeros(ne), np.zeros((0, 3)))
    assert bad == 5


@pytest.mark.parametrize("model", [ELASTIC, CAP])
def test_two_by_two_skips_only_unloaded_elements_at_rest(model):
    """With a rest counter the 2x2 kernel skips exactly the elements whose nodes did not move
    and whose points carry no stress, and every output is the one computing them gives: a
    moving element, its neighbours and a stressed element at rest are computed, the rest
    counted."""
    from pdfem.kernels.cap import cap_initial_state
    from pdfem.kernels.params import CAP_A, CAP_D, CAP_KAPPA0, CAP_R, CAP_T, CAP_TOL, CAP_W

    mat = material(model)
    if model == CAP:
        mat[0, [CAP_A, CAP_D, CAP_R, CAP_W, CAP_KAPPA0, CAP_T, CAP_TOL]] = [
            1.5e8, 5e-10, 2.0, 0.01, -3e9, 3e8, 0.0]
    xref, conn = grid(4, 3, 0.15, seed=4)
    ne, nn = conn.shape[0], xref.shape[0]
    du = np.zeros_like(xref)
    # Element 0's nodes move; element 10 is at rest but stressed; the others are untouched
    du[conn[0]] = np.random.default_rng(2).uniform(-2e-3, 2e-3, size=(4, 2))
    runs = []
    for rest in (None, np.zeros(1, np.int64)):
        st = State(nn, ne, 4)
        st.sig[10, :, 1] = -2.0e7
        if model == CAP:
            st.mstate = np.zeros((ne, 4, 6))
            for e in range(ne):
                for q in range(4):
                    cap_initial_state(mat[0], st.mstate[e, q])
        st.f[:] = 0.0
        bad = q4_forces_2x2(xref + du, du, conn, np.zeros(ne, np.int32), mat, st.sig,
                            st.mstate, st.hg, 0, 0, ne, st.f, st.ewint, st.ewp,
                            np.zeros((0, 3)), rest)
        assert bad == -1
        runs.append((st, rest))
    (a, _), (b, rest) = runs
    # Skipped: the elements with no node of element 0 (it moves them), but element 10
    moving = np.isin(conn, conn[0]).any(axis=1)
    assert moving.sum() == 4 and not moving[10]
    assert rest[0] == ne - 5
    for name in ("sig", "mstate", "f", "ewint", "ewp"):
        assert np.array_equal(getattr(a, name), getattr(b, name)), name
    # The computed ones did work: the moving element's stress and the stressed one's forces
    assert np.abs(b.sig[0]).max() > 0.0 and np.abs(b.f[conn[10]]).max() > 0.0
