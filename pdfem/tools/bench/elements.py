"""``pdfem bench elements``: element updates per second of the force kernels, numba vs numpy.

Each sample is one :func:`pdfem.tools.bench.numpy_element.bench_elements` call with one timed call
per implementation after an untimed warm-up call (numba compile or cache load excluded, as is
the first-touch cost of the arrays); the figure is the median of the samples. One process, one
thread: single-core figures.
"""

import math
import platform
import statistics

from pdfem.tools.bench.numpy_element import bench_elements
from pdfem.tools.bench.timing import median_call

# Integration rules and how the table names them
RULES = (("1pt", "1pt+hg"), ("2x2", "2x2"))


def machine():
    """One line naming the CPU, Python, numpy and numba."""
    import numba
    import numpy

    cpu = platform.processor() or platform.machine()
    try:
        with open("/proc/cpuinfo") as f:
            names = [ln.split(":", 1)[1].strip() for ln in f if ln.startswith("model name")]
        cpu = names[0] if names else cpu
    except OSError:
        pass
    return (f"machine: {cpu} | python {platform.python_version()} | numpy {numpy.__version__} | "
            f"numba {numba.__version__} | one core")


def mesh_shape(n):
    """(nx, ny), nx <= ny: exactly n quads if n has a divisor in [sqrt(n)/4, sqrt(n)], else ~n."""
    root = math.isqrt(n)
    for nx in range(root, max(1, root // 4) - 1, -1):
        if n % nx == 0:
            return nx, n // nx
    return root, -(-n // root)


def run_elements(n, repeat):
    """Median seconds per call of both rules, numba and numpy: list of row dicts."""
    nx, ny = mesh_shape(n)
    rows = []
    for rule, label in RULES:
        # repeat independent samples, each after its own warm-up call
        samples = [bench_elements(nx, ny, reps=1, rule=rule) for _ in range(repeat)]
        ne = samples[0]["elements"]
        med = {impl: statistics.median(s[impl] for s in samples) for impl in ("numba", "numpy")}
        for impl in ("numba", "numpy"):
            rows.append({"rule": label, "impl": impl, "elements": ne, "seconds": med[impl],
                         "speedup": med["numpy"] / med["numba"]})
    return rows, (nx, ny)


def print_elements(n, repeat, log=print):
    """Run the element benchmark and print its table; return (rows, C-yardstick dict or
    None)."""
    rows, (nx, ny) = run_elements(n, repeat)
    ne = rows[0]["elements"]
    log(f"pdfem bench elements: {ne} elements ({nx} x {ny} jittered unit quads), elastic, "
        f"median of {repeat} timed calls, each after a warm-up call (numba compile excluded)")
    log(machine())
    log(f"{'rule':<8}{'impl':<7}{'ms/call':>10}{'ns/elem-update':>16}{'Melem-updates/s':>17}")
    # One row per rule and implementation
    for r in rows:
        t = r["seconds"]
        log(f"{r['rule']:<8}{r['impl']:<7}{1e3 * t:>10.3f}{1e9 * t / ne:>16.2f}"
            f"{ne / t / 1e6:>17.3f}")
    # Speed-up lines: numba throughput over numpy throughput
    for r in rows[::2]:
        log(f"speed-up numba/numpy {r['rule']}: {r['speedup']:.2f}x")
    # The C yardstick of the 1-point elastic kernel (gcc -O3 -march=native), same mesh
    c = c_yardstick(nx, ny, repeat)
    if c is None:
        log("C yardstick: no C compiler found (gcc or cc), skipped")
    else:
        log(f"C yardstick 1pt+hg elastic (gcc -O3 -march=native): numba "
            f"{1e9 * c['numba'] / ne:.2f} ns/elem-update, C {1e9 * c['c'] / ne:.2f} "
            f"ns/elem-update, numba/C = {c['numba'] / c['c']:.2f} (target <= 1.6; largest "
            f"relative difference of the results {c['diff']:.1e})")
    # The points hourglass stiffness against the coefficient spring, same mesh and kernel
    pts = points_cost(nx, ny, repeat)
    line = (f"1pt+hg hourglass_stiffness points: numba {1e9 * pts['points'] / ne:.2f} "
            f"ns/elem-update = {pts['points'] / pts['coefficient']:.2f}x the coefficient "
            f"spring's ({1e9 * pts['coefficient'] / ne:.2f})")
    if c is not None:
        line += f", {pts['points'] / c['c']:.2f}x the C yardstick"
    log(line)
    return rows, c


def points_cost(nx, ny, repeat):
    """Median seconds per call of the numba 1-point elastic kernel with the coefficient spring
    and with the points hourglass stiffness on one bench mesh (dict)."""
    import numpy as np

    from pdfem.kernels.element_1pt import (
        HG_COEFFICIENT,
        HG_COLS_POINTS,
        HG_POINTS,
        hourglass_reference,
        q4_forces_1pt,
    )
    from pdfem.kernels.params import BULK, ELASTIC, MODEL, NPAR, RHO, SHEAR
    from pdfem.tools.bench.numpy_element import bench_mesh

    x, conn = bench_mesh(nx, ny)
    ne = conn.shape[0]
    mat = np.zeros((1, NPAR))
    mat[0, [MODEL, RHO, BULK, SHEAR]] = [ELASTIC, 2000.0, 1e10, 6e9]
    du = np.random.default_rng(1).uniform(-1e-6, 1e-6, size=x.shape)
    hg = np.zeros((ne, HG_COLS_POINTS))
    hourglass_reference(x, conn, 0.1, 0, ne, hg)
    out = {}
    # One kernel, two stiffnesses: the spring reads hg's first six columns only
    for name, model in (("coefficient", HG_COEFFICIENT), ("points", HG_POINTS)):
        args = (x + du, du, conn, np.zeros(ne, np.int32), mat, np.zeros((ne, 1, 4)),
                np.zeros((ne, 1, 0)), hg, model, 0, ne, np.zeros_like(x), np.zeros(ne),
                np.zeros(ne), np.zeros((0, 3)))
        out[name] = median_call(q4_forces_1pt, args, repeat)
    return out


def c_yardstick(nx, ny, repeat):
    """Median seconds per call of the numba 1-point kernel and its C twin on one mesh, and the
    largest relative difference of their stresses, forces and stress work (or None)."""

    import numpy as np

    from pdfem.kernels.element_1pt import q4_forces_1pt
    from pdfem.kernels.params import BULK, ELASTIC, MODEL, NPAR, RHO, SHEAR
    from pdfem.tools.bench.cyardstick import load
    from pdfem.tools.bench.numpy_element import bench_mesh, hourglass_reference

    cfn = load()
    if cfn is None:
        return None
    x, conn = bench_mesh(nx, ny)
    ne = conn.shape[0]
    mat = np.zeros((1, NPAR))
    mat[0, [MODEL, RHO, BULK, SHEAR]] = [ELASTIC, 2000.0, 1e10, 6e9]
    du = np.random.default_rng(1).uniform(-1e-6, 1e-6, size=x.shape)
    hg = hourglass_reference(x, conn, 0.1)
    out = {}
    for name, fn in (("numba", q4_forces_1pt), ("c", cfn)):
        sig, ewint = np.zeros((ne, 1, 4)), np.zeros(ne)
        f = np.zeros_like(x)
        args = (x + du, du, conn, np.zeros(ne, np.int32), mat, sig, np.zeros((ne, 1, 0)), hg,
                0, 0, ne, f, ewint, np.zeros(ne), np.zeros((0, 3)))
        fn(*args)  # warm-up; also the state compared below (one call from zero)
        res = (sig.copy(), f.copy(), ewint.copy())
        out[name] = median_call(fn, args, repeat, warm=False)
        out[name + "_res"] = res
    out["diff"] = max(float(np.max(np.abs(a - b)) / max(np.max(np.abs(a)), 1e-300))
                      for a, b in zip(out["numba_res"], out["c_res"], strict=True))
    return out
