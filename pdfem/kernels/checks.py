"""Cheap per-step checks of the guards: the first non-finite entry, the Jacobians of an
element (pdfem.guards)."""

import numpy as np
from numba import njit


@njit(cache=True)
def first_nonfinite(a, n):
    """Index of the first row i < n of a (rows, cols) array holding a NaN or inf; -1 if none."""
    for i in range(n):
        for j in range(a.shape[1]):
            if not np.isfinite(a[i, j]):
                return i
    return -1


@njit(cache=True)
def corner_jacobians(x, conn, e, out):
    """Twice the area of each corner triangle of element e (its Jacobian at the corners, x 4)
    into out (4,): all > 0 for a valid counter-clockwise quad; return the smallest."""
    lo = np.inf
    for k in range(4):
        a = conn[e, k]
        b = conn[e, (k + 1) % 4]
        c = conn[e, (k + 3) % 4]
        j = (x[b, 0] - x[a, 0]) * (x[c, 1] - x[a, 1]) - (x[b, 1] - x[a, 1]) * (x[c, 0] - x[a, 0])
        out[k] = j
        lo = min(lo, j)
    return lo
