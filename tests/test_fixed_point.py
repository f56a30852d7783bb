"""Fixed-point column sums of the per-step energy-drift check (pdfem.energy.fixed_point_sums):
within n q / 2 of the exact sums, independent of the order and split of the rows, no overflow
at the worst case, None for a non-finite value."""

import math

import numpy as np
from mpi4py import MPI

from pdfem.energy import QBITS, fixed_point_sums

SELF = MPI.COMM_SELF


def _quantum(col, n):
    v = float(np.abs(col).max())
    return math.ldexp(1.0, math.frexp(v)[1] - QBITS + (n - 1).bit_length())


def test_sums_are_within_n_q_over_two_of_the_exact_ones():
    rng = np.random.default_rng(5)
    n = 5000
    # Columns of positive, mixed-sign and widely spread values (many decades)
    rows = np.stack([rng.uniform(0, 1e3, n), rng.normal(0, 1e-6, n),
                     10.0 ** rng.uniform(-30, 5, n) * rng.choice([-1, 1], n),
                     np.zeros(n)], axis=1)
    out = fixed_point_sums(rows, SELF, n)
    for j in range(rows.shape[1]):
        exact = math.fsum(rows[:, j])
        bound = 0.5 * n * _quantum(rows[:, j], n) if rows[:, j].any() else 0.0
        assert abs(out[j] - exact) <= bound + 1e-15 * abs(exact), j
    assert out[3] == 0.0


def test_order_and_split_do_not_change_a_bit():
    rng = np.random.default_rng(6)
    rows = rng.normal(0, 1, (3000, 3)) * np.array([1e-3, 1.0, 1e9])
    whole = fixed_point_sums(rows, SELF, 3000)
    assert fixed_point_sums(rows[rng.permutation(3000)], SELF, 3000) == whole
    # Two "ranks" with the quantum of the whole (their largest magnitude is the global one):
    # the multiples add as integers, so the split gives the same sum
    big = np.abs(rows).argmax(axis=0)
    part = np.zeros(3000, bool)
    part[rng.choice(3000, 1200, replace=False)] = True
    part[big] = True
    q = np.array([_quantum(rows[:, j], 3000) for j in range(3)])
    ka = np.rint(rows[part] / q).astype(np.int64).sum(axis=0)
    kb = np.rint(rows[~part] / q).astype(np.int64).sum(axis=0)
    assert [float(int(ka[j] + kb[j])) * q[j] for j in range(3)] == whole


def test_worst_case_cannot_overflow():
    # Every row at the column's largest magnitude: n multiples of 2^(QBITS - ceil(log2 n))
    for n in (1, 2, 3, 1000, 1024, 1025, 100_000):
        rows = np.full((n, 2), 0.99999999)
        rows[:, 1] = -3.0e300
        out = fixed_point_sums(rows, SELF, n)
        assert math.isclose(out[0], 0.99999999 * n, rel_tol=1e-12)
        assert math.isclose(out[1], -3.0e300 * n, rel_tol=1e-12)


def test_a_non_finite_value_is_refused():
    for bad in (np.nan, np.inf, -np.inf):
        rows = np.ones((10, 2))
        rows[3, 1] = bad
        assert fixed_point_sums(rows, SELF, 10) is None
    assert fixed_point_sums(np.empty((0, 2)), SELF, 0) == [0.0, 0.0]


def test_the_samples_scale_bounds_the_drift_checks_error():
    # The drift check's error is balance() with the samples' largest scale in the floor: the
    # same as the samples' own error while that scale is not larger, and bounded by it else
    import pdfem.effects  # noqa: F401  (the effects declare their terms)
    from pdfem.energy import ROLES, balance, balance_scale

    TERMS = tuple(ROLES)
    rng = np.random.default_rng(9)
    for floor in (0.0, 1e-3, 1e3):
        ref = {t: float(v) for t, v in zip(TERMS, rng.normal(0, 10, len(TERMS)), strict=True)}
        for _ in range(20):
            terms = {t: ref[t] + float(rng.normal(0, 3)) for t in TERMS}
            small = min(balance_scale(terms, ref, floor), 1e-6)
            assert balance(terms, ref, max(floor, small))[1] == balance(terms, ref, floor)[1]
    terms = {t: ref[t] + 1.0 for t in TERMS}
    assert balance(terms, ref, 1e6)[1] <= abs(balance(terms, ref)[0] - balance(ref, ref)[0]) / 1e6
