"""Contact keys sort lexicographically, packed or not (the order forces are added in)."""

import numpy as np

from pdfem.effects.contact_candidates import lexorder


def _reference(keys):
    return np.lexsort((keys[:, 3], keys[:, 2], keys[:, 1], keys[:, 0]))


def test_packed_sort_matches_lexsort_with_duplicates_and_wall_keys():
    rng = np.random.default_rng(4)
    keys = np.stack([rng.integers(0, 5000, 20000), rng.integers(0, 600, 20000),
                     rng.integers(-4, 5000, 20000), rng.integers(0, 600, 20000)], axis=1)
    keys[::7] = keys[3]  # duplicates keep their input order (stable)
    assert np.array_equal(lexorder(keys), _reference(keys))


def test_spans_beyond_int64_fall_back_to_lexsort():
    rng = np.random.default_rng(5)
    keys = rng.integers(-2**40, 2**40, size=(3000, 4))
    assert np.array_equal(lexorder(keys), _reference(keys))


def test_empty_and_single_rows():
    assert lexorder(np.zeros((0, 4), np.int64)).shape == (0,)
    assert list(lexorder(np.array([[3, 1, -1, 0]]))) == [0]
