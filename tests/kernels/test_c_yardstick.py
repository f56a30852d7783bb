"""The C yardstick and the numba 1-point element kernel compute the same numbers."""

import numpy as np
import pytest

from pdfem.bench.cyardstick import load
from pdfem.bench.numpy_element import bench_mesh
from pdfem.kernels.element import q4_forces_1pt
from pdfem.kernels.params import BULK, ELASTIC, MODEL, NPAR, RHO, SHEAR


def test_c_twin_matches_numba_to_1e12():
    cfn = load()
    if cfn is None:
        pytest.skip("no C compiler")
    x, conn = bench_mesh(40, 30)
    ne = conn.shape[0]
    mat = np.zeros((1, NPAR))
    mat[0, [MODEL, RHO, BULK, SHEAR]] = [ELASTIC, 2000.0, 1e10, 6e9]
    rng = np.random.default_rng(5)
    # A large rotation-carrying increment and non-zero starting stress and hourglass forces
    du = rng.uniform(-2e-3, 2e-3, size=x.shape)
    sig0, hg0 = rng.uniform(-1e7, 1e7, (ne, 1, 4)), rng.uniform(-10.0, 10.0, (ne, 2))
    out = []
    for fn in (q4_forces_1pt, cfn):
        sig, hgq, f, ew = sig0.copy(), hg0.copy(), np.zeros_like(x), np.zeros(ne)
        bad = fn(x + du, du, conn, np.zeros(ne, np.int32), mat, sig, np.zeros((ne, 1, 0)), hgq,
                 0.1, 0, ne, f, ew, np.zeros(ne), np.zeros((0, 3)))
        assert bad == -1
        out.append((sig, hgq, f, ew))
    for a, b in zip(*out, strict=True):
        assert np.max(np.abs(a - b)) <= 1e-12 * np.max(np.abs(a))
