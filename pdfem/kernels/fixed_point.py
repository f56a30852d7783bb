"""Fixed-point column sums for the energy-drift check (pdfem.energy.fixed_point_sums).

Every value of column j is rounded to a multiple of the power of two q_j =
2^(e_j - qbits + lift), M_j < 2^e_j being the column's largest magnitude over all ranks and
2^lift >= the number of rows over all ranks, so that the int64 sum of the multiples cannot
overflow for qbits <= 62; integer sums are exact in any order. Energies in J/m.
"""

import math

import numpy as np
from numba import njit


@njit(cache=True)
def column_extent(rows, out):
    """out[j] = max_i |rows[i, j]|; out[nt] = 1.0 when a value is not finite, else 0.0."""
    nt = rows.shape[1]
    for j in range(nt + 1):
        out[j] = 0.0
    for i in range(rows.shape[0]):
        for j in range(nt):
            v = rows[i, j]
            if not math.isfinite(v):
                out[nt] = 1.0
            elif abs(v) > out[j]:
                out[j] = abs(v)


@njit(cache=True)
def column_multiples(rows, top, lift, qbits, q, k):
    """q[j] = the quantum of column j from its global extent top[j] (1.0 for an all-zero
    column); k[j] = sum_i rint(rows[i, j] / q[j]) (int64)."""
    nt = rows.shape[1]
    for j in range(nt):
        if top[j] > 0.0:
            _, e = math.frexp(top[j])
            q[j] = math.ldexp(1.0, e - qbits + lift)
        else:
            q[j] = 1.0
        k[j] = 0
    for i in range(rows.shape[0]):
        for j in range(nt):
            k[j] += np.int64(np.rint(rows[i, j] / q[j]))
