"""Cheap per-step check of the guards (pdfem.guards): the first non-finite entry."""

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
