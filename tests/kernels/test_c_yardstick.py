"""The C yardsticks and the numba element kernels (1-point elastic, 2x2 cap) compute the same
numbers."""

import numpy as np
import pytest

from pdfem.kernels.cap import CAP_NST
from pdfem.kernels.element import q4_forces_2x2
from pdfem.kernels.element_1pt import q4_forces_1pt
from pdfem.kernels.material import material_initial_state
from pdfem.kernels.params import BULK, CAP_T, ELASTIC, MODEL, NPAR, RHO, SHEAR
from pdfem.material_point import cap_params_from_table
from pdfem.tools.bench.cap_yardstick import HMX, cap_state
from pdfem.tools.bench.cyardstick import load
from pdfem.tools.bench.numpy_element import bench_mesh, hourglass_reference


@pytest.mark.parametrize("model", [0, 1, 2])
def test_c_twin_matches_numba_to_1e12(model):
    cfn = load()
    if cfn is None:
        pytest.skip("no C compiler")
    x, conn = bench_mesh(40, 30)
    ne = conn.shape[0]
    mat = np.zeros((1, NPAR))
    mat[0, [MODEL, RHO, BULK, SHEAR]] = [ELASTIC, 2000.0, 1e10, 6e9]
    rng = np.random.default_rng(5)
    # A large rotation-carrying increment, a non-zero starting stress and hourglass modes
    # measured from a reference other than the last positions
    du = rng.uniform(-2e-3, 2e-3, size=x.shape)
    sig0 = rng.uniform(-1e7, 1e7, (ne, 1, 4))
    hg = hourglass_reference(x + rng.uniform(-0.05, 0.05, size=x.shape), conn, 0.1)
    out = []
    for fn in (q4_forces_1pt, cfn):
        sig, f, ew = sig0.copy(), np.zeros_like(x), np.zeros(ne)
        bad = fn(x + du, du, conn, np.zeros(ne, np.int32), mat, sig, np.zeros((ne, 1, 0)), hg,
                 model, 0, ne, f, ew, np.zeros(ne), np.zeros((0, 3)))
        assert bad == -1
        out.append((sig, f, ew))
    for a, b in zip(*out, strict=True):
        assert np.max(np.abs(a - b)) <= 1e-12 * np.max(np.abs(a))


# ---- the 2x2 element with the Sandler-Rubin cap model (pdfem/tools/bench/c/q4_2x2_cap.c) ----

STEEL = {"model": "cap", "density": 7850.0, "bulk": 160.0e9, "shear": 79.0e9, "A": 1.0e9,
         "B": 1.0e-9, "C": 5.0e8, "D": 1.0e-10, "R": 2.0, "W": 0.001, "kappa0": -5.0e9}


def _cap_c():
    """The C twin of q4_forces_2x2, or skip."""
    cfn = load("q4_2x2_cap")
    if cfn is None:
        pytest.skip("no C compiler")
    return cfn


def _close(a, b):
    """max |a - b| <= 1e-12 max |a| (exact equality for an all-zero a)."""
    return np.max(np.abs(a - b)) <= 1e-12 * np.max(np.abs(a))


def _mixed_table():
    """HMX-like cap, steel-like cap, an elastic row, and the HMX-like cap with kappa0 > 0 (the
    1979 step at I1 = 0) and a tension cut-off below the envelope apex."""
    mat = np.zeros((4, NPAR))
    mat[0] = cap_params_from_table(HMX)
    mat[1] = cap_params_from_table(STEEL)
    mat[2, [MODEL, RHO, BULK, SHEAR]] = [ELASTIC, 1900.0, 12.7e9, 4.4e9]
    mat[3] = cap_params_from_table({**HMX, "kappa0": 2.0e7, "tension_cutoff": 5.0e7})
    return mat


def _call_2x2(fn, x, du, conn, emat, mat, state):
    """One call on the state tuple (sig, mst, ewint, ewp) in place; returns (bad, f)."""
    sig, mst, ewint, ewp = state
    f = np.zeros_like(x)
    bad = fn(x, du, conn, emat, mat, sig, mst, np.zeros((0, 6)), 0, 0, conn.shape[0], f,
             ewint, ewp, np.zeros((0, 3)))
    return bad, f


def _fresh(ne, emat, mat):
    """Zero stress and work, initial cap state."""
    mst = np.zeros((ne, 4, CAP_NST))
    material_initial_state(mst, emat, mat)
    return np.zeros((ne, 4, 4)), mst, np.zeros(ne), np.zeros(ne)


def test_c_2x2_cap_matches_numba_after_one_call():
    cfn = _cap_c()
    s = cap_state(40, 30)
    ne = s["emat"].shape[0]
    out = []
    for fn in (q4_forces_2x2, cfn):
        state = (s["sig"].copy(), s["mst"].copy(), np.zeros(ne), np.zeros(ne))
        bad, f = _call_2x2(fn, s["x"], s["du"], s["conn"], s["emat"], s["mat"], state)
        assert bad == -1
        out.append((*state, f))
    for a, b in zip(*out, strict=True):
        assert _close(a, b)
    # The call was plastic at most points: cap and envelope
    changed = np.any(out[0][1] != s["mst"], axis=2)
    assert changed.mean() > 0.5 and out[0][3].sum() > 0.0


def test_c_2x2_cap_matches_numba_on_a_loading_path():
    """20 calls from rest, compared after each: first (nearly) elastic, then envelope
    dilatancy, the tension cut-off and cap compaction, on a mix of caps and an elastic."""
    cfn = _cap_c()
    x0, conn = bench_mesh(40, 30)
    ne = conn.shape[0]
    mat = _mixed_table()
    rng = np.random.default_rng(3)
    emat = rng.choice(np.array([0, 0, 0, 1, 2, 3], np.int32), ne)
    # Compression at the left, tension at the right, shear growing with y, node jitter
    y = x0[:, 1]
    du = np.stack([1.5e-3 * y, -2e-3 * y * (1.0 - 1.5 * x0[:, 0] / 40.0)], axis=1)
    du += rng.uniform(-1e-3, 1e-3, x0.shape)
    states = [_fresh(ne, emat, mat) for _ in range(2)]
    kappa0 = states[0][1][:, :, 0].copy()
    yielded = []
    x = x0
    for k in range(20):
        x = x + du
        before = states[0][1].copy()
        fs = []
        for fn, state in zip((q4_forces_2x2, cfn), states, strict=True):
            bad, f = _call_2x2(fn, x, du, conn, emat, mat, state)
            assert bad == -1
            fs.append(f)
        for a, b in zip((*states[0], fs[0]), (*states[1], fs[1]), strict=True):
            assert _close(a, b), k
        yielded.append(np.any(states[0][1] != before, axis=2)[emat == 0].mean())
    # HMX plasticity grew from (almost) nothing to most points, in every mode of the cap
    sig, mst, ewint, ewp = states[0]
    hmx = emat == 0
    kap = mst[:, :, 0]
    i1 = sig[:, :, 0] + sig[:, :, 1] + sig[:, :, 3]
    assert yielded[0] < 0.05 and yielded[-1] > 0.5
    assert ewp.sum() > 0.0 and np.all(ewp >= -1e-9 * ewp.max())
    assert np.mean(kap[hmx] < kappa0[hmx]) > 0.1  # cap compaction hardened kappa
    assert np.mean(kap[hmx] > kappa0[hmx]) > 0.1  # envelope dilatancy retracted the cap
    assert np.any(i1[hmx] == mat[0, CAP_T])  # stress held at the tension cut-off
    assert np.all(mst[emat == 2] == 0.0)  # elastic points keep no state


@pytest.mark.parametrize("fault", ["inverted", "nan-stress", "unknown-model"])
def test_c_2x2_cap_reports_the_same_failing_element(fault):
    cfn = _cap_c()
    x0, conn = bench_mesh(12, 10)
    ne = conn.shape[0]
    mat = _mixed_table()
    emat = np.zeros(ne, np.int32)
    du = np.stack([1e-3 * x0[:, 1], -5e-3 * x0[:, 1]], axis=1)
    state0 = _fresh(ne, emat, mat)
    if fault == "inverted":
        # An interior node pushed up-right past its neighbours inverts the elements where it
        # is node 3 or node 0; the first of them (node 3, one row lower) is reported
        n = 5 * 13 + 6
        du[n] = [2.5, 2.5]
        want = int(np.nonzero(conn[:, 3] == n)[0][0])
    elif fault == "nan-stress":
        want = 57
        state0[0][want, 2, 0] = np.nan
    else:
        want = 80
        mat = np.vstack([mat, mat[0]])
        mat[3, MODEL] = 7.0
        emat[want] = 3
    out = []
    for fn in (q4_forces_2x2, cfn):
        state = tuple(a.copy() for a in state0)
        bad, f = _call_2x2(fn, x0 + du, du, conn, emat, mat, state)
        assert bad == want
        out.append((*state, f))
    for a, b in zip(*out, strict=True):
        assert np.array_equal(np.isnan(a), np.isnan(b))
        assert _close(np.nan_to_num(a), np.nan_to_num(b))


# ---- the contact pass (pdfem/tools/bench/c/contact_pass.c) ----


def test_contact_pass_twin_gives_numba_bits_on_a_settled_bed(tmp_path):
    # A 300-grain cap bed of pdfem bench contact, a few steps in: the C twin of the pass on
    # that step's candidates, history and positions writes the same rows, bit for bit
    from mpi4py import MPI

    from pdfem.scene import parse_scene
    from pdfem.solver import Simulation
    from pdfem.tools.bench.beds import bed_scene, inflate_grains
    from pdfem.tools.bench.pass_yardstick import pass_yardstick

    if load("contact_pass") is None:
        pytest.skip("no C compiler")
    scene = parse_scene(bed_scene(300, str(tmp_path), material="cap"), str(tmp_path))
    sim = Simulation(scene, MPI.COMM_SELF, init_state=inflate_grains(1.12))
    for _ in range(5):
        sim.step()
    y = pass_yardstick(sim, 1)
    assert y["same"] and y["unsupported"] == 0
    assert y["contacts"] > 2.0 * 300 and y["evaluated"] > y["contacts"]
    assert y["candidates"] > y["evaluated"]
