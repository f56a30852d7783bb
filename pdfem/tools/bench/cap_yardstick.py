"""The numba 2x2 element kernel with cap plasticity against its C twin (bench/c/q4_2x2_cap.c).

A jittered bench_mesh of an HMX-like cap material (the [materials.hmx] table of the shock test
scenes) is first squeezed by the numba kernel, untimed, to a state where the cap (strong
compression, at the left) and the envelope (strong shear, at the top right) are active; from
that state both kernels take the same further increment (compressive strain and simple shear
of a few 1e-4 plus a small random jitter): about 70 % of the points yield in every timed call
(cap about 2/3 of all points, envelope about 1/8), the rest stays elastic. Every timed call
starts from a copy of that state (copied outside the timed region): the same work each time.
"""

import time

import numpy as np

# HMX-like cap (tests/scenes.py SHOCK_MATERIALS, [materials.hmx]), SI units
HMX = {"model": "cap", "density": 1900.0, "bulk": 12.7e9, "shear": 4.4e9, "A": 2.0e8,
       "B": 2.0e-9, "C": 1.5e8, "D": 5.0e-10, "R": 2.0, "W": 0.05, "kappa0": -1.0e9}
# Squeeze before the timed calls: calls, strain per call (compression at x = 0, top shear)
PRELOAD_CALLS = 10
PRELOAD_STRAIN = (3.5e-3, 6.0e-3)
# Timed increment: strain per call and jitter of the node increments [element sizes]
STRAIN = (3.0e-4, 3.0e-4)
JITTER = 3.0e-5


def hmx_params():
    """(1, NPAR) material table holding the HMX-like cap row."""
    from pdfem.material_point import cap_params_from_table

    return cap_params_from_table(HMX, "materials.hmx")[None, :]


def squeeze(x, eps, gam):
    """Node increments (nn, 2): compression in y, a strain -eps at x = 0 falling to -0.4 eps
    at the right, plus a simple shear growing from 0 at y = 0 to gam at the top
    (du_x = gam y^2 / (2 ymax)): cap at the left, envelope at the top right, elastic at the
    bottom right."""
    y = x[:, 1]
    ey = eps * (1.0 - 0.6 * x[:, 0] / x[:, 0].max())
    return np.stack([0.5 * gam * y * y / y.max(), -ey * y], axis=1)


def cap_state(nx, ny, seed=1):
    """Mesh, material and the squeezed state: dict of the kernel arguments before a call."""
    from pdfem.kernels.cap import CAP_NST
    from pdfem.kernels.element import q4_forces_2x2
    from pdfem.kernels.material import material_initial_state
    from pdfem.tools.bench.numpy_element import bench_mesh

    x, conn = bench_mesh(nx, ny)
    ne = conn.shape[0]
    mat = hmx_params()
    emat = np.zeros(ne, np.int32)
    sig = np.zeros((ne, 4, 4))
    mst = np.zeros((ne, 4, CAP_NST))
    material_initial_state(mst, emat, mat)
    # Untimed squeeze with the numba kernel
    dpre = squeeze(x, *PRELOAD_STRAIN)
    for _ in range(PRELOAD_CALLS):
        x = x + dpre
        bad = q4_forces_2x2(x, dpre, conn, emat, mat, sig, mst, np.zeros((0, 6)), 0, 0, ne,
                            np.zeros_like(x), np.zeros(ne), np.zeros(ne), np.zeros((0, 3)))
        if bad != -1:
            raise RuntimeError(f"element {bad} failed in the squeeze")
    # The increment of the timed calls
    du = squeeze(x, *STRAIN) + np.random.default_rng(seed).uniform(-JITTER, JITTER, x.shape)
    return {"x": x + du, "du": du, "conn": conn, "emat": emat, "mat": mat, "sig": sig,
            "mst": mst}


def _call(fn, s, work):
    """One kernel call from state s on the work arrays (reset before, outside any timing)."""
    sig, mst, f, ewint, ewp = work
    np.copyto(sig, s["sig"])
    np.copyto(mst, s["mst"])
    f.fill(0.0)
    ewint.fill(0.0)
    ewp.fill(0.0)
    t0 = time.perf_counter()
    bad = fn(s["x"], s["du"], s["conn"], s["emat"], s["mat"], sig, mst, np.zeros((0, 6)), 0, 0,
             s["emat"].shape[0], f, ewint, ewp, np.zeros((0, 3)))
    t = time.perf_counter() - t0
    if bad != -1:
        raise RuntimeError(f"element {bad} failed")
    return t


def c_yardstick_cap(nx, ny, repeat):
    """Median seconds per call of numba q4_forces_2x2 and its C twin on a cap material (dict),
    or None without a C compiler.

    Keys: elements, numba, c (median seconds of ``repeat`` timed calls after a warm-up call,
    the two kernels alternating), ratio (numba / c), yield_fraction (points whose cap state
    changed in a call), diff (largest relative difference max|a - b| / max|a| of sig, mst, f,
    ewint, ewp after one call from the same state) and diffs (per array).
    """
    from pdfem.kernels.element import q4_forces_2x2
    from pdfem.tools.bench.cyardstick import load

    cfn = load("q4_2x2_cap")
    if cfn is None:
        return None
    s = cap_state(nx, ny)
    ne = s["emat"].shape[0]
    kernels = {"numba": q4_forces_2x2, "c": cfn}
    work = {k: (np.empty_like(s["sig"]), np.empty_like(s["mst"]), np.empty_like(s["x"]),
                np.empty(ne), np.empty(ne)) for k in kernels}
    # Warm-up: also the results compared below
    for k, fn in kernels.items():
        _call(fn, s, work[k])
    names = ("sig", "mst", "f", "ewint", "ewp")
    diffs = {n: float(np.max(np.abs(a - b)) / max(np.max(np.abs(a)), 1e-300))
             for n, a, b in zip(names, work["numba"], work["c"], strict=True)}
    changed = np.any(work["numba"][1] != s["mst"], axis=2)
    # Timed calls, alternating the kernels
    times = {k: [] for k in kernels}
    for _ in range(repeat):
        for k, fn in kernels.items():
            times[k].append(_call(fn, s, work[k]))
    out = {k: sorted(t)[len(t) // 2] for k, t in times.items()}
    out.update(elements=ne, ratio=out["numba"] / out["c"],
               yield_fraction=float(changed.mean()), diff=max(diffs.values()), diffs=diffs)
    return out
