"""Tests of the cell grid and the cell-to-rank partitions (serial, no MPI)."""

import itertools

import numpy as np
import pytest

from partition import (
    CellGrid,
    imbalance,
    loads,
    needs_rebalance,
    partition,
    rcb,
    strips,
)
from partition.strips import cut_line

GRIDS = [(1, 1), (1, 5), (5, 1), (5, 3), (7, 11), (16, 16)]
METHODS = ["strips", "rcb"]


def _bed(nx, ny, rows, seed=0):
    """Cell weights of a granular bed filling the lowest ``rows`` rows, zero above."""
    rng = np.random.default_rng(seed)
    w = np.zeros((ny, nx))
    w[:rows] = rng.uniform(0.5, 1.5, size=(rows, nx))
    return w.ravel()


def _optimal_bottleneck(w, k):
    """Smallest possible max group sum of k contiguous groups (brute-force DP)."""
    prefix = np.concatenate([[0.0], np.cumsum(w)])
    best = np.full(len(w) + 1, np.inf)
    best[0] = 0.0
    for _ in range(k):
        best = np.array(
            [
                min(max(best[i], prefix[j] - prefix[i]) for i in range(j + 1))
                for j in range(len(w) + 1)
            ]
        )
    return best[-1]


# ---------------------------------------------------------------- CellGrid


def test_grid_sizes():
    g = CellGrid((0.0, 0.0, 3.0, 2.0), 1.0)
    assert (g.nx, g.ny, g.ncell, g.hx, g.hy) == (3, 2, 6, 1.0, 1.0)
    # Cells never narrower than cell_size
    g = CellGrid((0.0, 0.0, 3.0, 1.0), 0.9)
    assert (g.nx, g.ny) == (3, 1) and g.hx == 1.0 and g.hy == 1.0
    g = CellGrid((-1.0e-3, 0.0, 1.0e-3, 1.0e-3), 7.0e-4)
    assert (g.nx, g.ny) == (2, 1) and g.hx >= 7.0e-4 and g.hy >= 7.0e-4
    # Box smaller than a cell: one cell
    g = CellGrid((0.0, 0.0, 0.5, 0.5), 1.0)
    assert (g.nx, g.ny, g.ncell) == (1, 1, 1)


def test_grid_bad_input():
    with pytest.raises(ValueError):
        CellGrid((0.0, 0.0, 0.0, 1.0), 1.0)
    with pytest.raises(ValueError):
        CellGrid((0.0, 0.0, 1.0, 1.0), 0.0)
    with pytest.raises(ValueError):
        CellGrid((0.0, 0.0, 4.0, 3.0), 1.0).neighbours(12)


def test_cell_of():
    g = CellGrid((0.0, 0.0, 3.0, 2.0), 1.0)
    pts = [
        [0.5, 0.5],
        [2.5, 1.5],
        [1.0, 1.0],
        [0.0, 0.0],
        [3.0, 2.0],
        [-1.0, -1.0],
        [10.0, 0.5],
        [1.5, 99.0],
        [2.999, 0.001],
    ]
    got = g.cell_of(np.array(pts))
    assert got.dtype == np.int64
    assert got.tolist() == [0, 5, 4, 0, 5, 0, 2, 4, 2]
    assert g.cell_of(np.zeros((0, 2))).shape == (0,)


def test_neighbours():
    g = CellGrid((0.0, 0.0, 4.0, 3.0), 1.0)  # 4 x 3 cells
    assert g.neighbours(0).tolist() == [0, 1, 4, 5]
    assert g.neighbours(5).tolist() == [0, 1, 2, 4, 5, 6, 8, 9, 10]
    assert g.neighbours(11).tolist() == [6, 7, 10, 11]
    assert g.neighbours(3).tolist() == [2, 3, 6, 7]
    assert g.neighbours(7).tolist() == [2, 3, 6, 7, 10, 11]
    assert g.neighbours(np.int64(4)).dtype == np.int64
    # Single-cell and single-row grids
    assert CellGrid((0.0, 0.0, 1.0, 1.0), 1.0).neighbours(0).tolist() == [0]
    assert CellGrid((0.0, 0.0, 5.0, 1.0), 1.0).neighbours(2).tolist() == [1, 2, 3]


def test_ring():
    g = CellGrid((0.0, 0.0, 4.0, 3.0), 1.0)
    assert g.ring([5]).tolist() == [0, 1, 2, 4, 6, 8, 9, 10]
    assert g.ring([0, 1]).tolist() == [2, 4, 5, 6]
    assert g.ring([3, 0]).tolist() == [1, 2, 4, 5, 6, 7]
    assert g.ring([1, 2, 5, 6]).tolist() == [0, 3, 4, 7, 8, 9, 10, 11]
    assert g.ring(np.arange(12)).tolist() == []
    assert g.ring([]).tolist() == []
    assert g.ring([5]).dtype == np.int64
    # The ring of one cell is its neighbourhood without itself
    for c in range(g.ncell):
        assert g.ring([c]).tolist() == [n for n in g.neighbours(c).tolist() if n != c]


def test_centres():
    g = CellGrid((1.0, 2.0, 4.0, 4.0), 1.0)
    c = g.centres()
    assert c.shape == (6, 2)
    assert np.allclose(c[[0, 2, 3, 5]], [[1.5, 2.5], [3.5, 2.5], [1.5, 3.5], [3.5, 3.5]])
    assert g.cell_of(c).tolist() == list(range(6))


# ---------------------------------------------------------------- balance


def test_loads_and_imbalance():
    w = [1.0, 2.0, 3.0, 4.0]
    owner = [0, 0, 1, 1]
    assert loads(w, owner, 2).tolist() == [3.0, 7.0]
    assert loads(w, owner, 3).tolist() == [3.0, 7.0, 0.0]
    assert imbalance(w, owner, 2) == pytest.approx(1.4)
    assert imbalance(w, owner, 3) == pytest.approx(7.0 / (10.0 / 3.0))
    assert imbalance(np.zeros(4), owner, 2) == 1.0
    assert needs_rebalance(w, owner, 2, 1.3)
    assert not needs_rebalance(w, owner, 2, 1.5)
    with pytest.raises(ValueError):
        loads(w, [0, 0, 1, 2], 2)


def test_partition_dispatch():
    w = np.ones(12)
    assert np.array_equal(partition("strips", w, 4, 3, 2), strips(w, 4, 3, 2))
    assert np.array_equal(partition("strips", w, 4, 3, 3, axis=1), strips(w, 4, 3, 3, axis=1))
    assert np.array_equal(partition("rcb", w, 4, 3, 3), rcb(w, 4, 3, 3))
    with pytest.raises(ValueError, match="metis"):
        partition("metis", w, 4, 3, 2)


@pytest.mark.parametrize("method", METHODS)
def test_bad_weights(method):
    with pytest.raises(ValueError):
        partition(method, np.ones(5), 2, 3, 2)
    with pytest.raises(ValueError):
        partition(method, -np.ones(6), 2, 3, 2)
    with pytest.raises(ValueError):
        partition(method, np.full(6, np.nan), 2, 3, 2)
    with pytest.raises(ValueError):
        partition(method, np.ones(6), 2, 3, 0)


# ---------------------------------------------------------------- partitions


@pytest.mark.parametrize("method", METHODS)
@pytest.mark.parametrize("nx,ny", GRIDS)
def test_every_cell_owned_once(method, nx, ny):
    rng = np.random.default_rng(nx * 100 + ny)
    for nranks in [1, 2, 3, 4, 7, 9, 64]:
        w = rng.random(nx * ny) * (rng.random(nx * ny) < 0.6)
        owner = partition(method, w, nx, ny, nranks)
        assert owner.shape == (nx * ny,) and owner.dtype == np.int32
        assert owner.min() >= 0 and owner.max() < nranks
        # Loads account for every cell exactly once
        assert np.isclose(loads(w, owner, nranks).sum(), w.sum())


@pytest.mark.parametrize("method", METHODS)
def test_deterministic(method):
    w = _bed(23, 17, 9, seed=3)
    first = partition(method, w, 23, 17, 6)
    for _ in range(3):
        assert np.array_equal(partition(method, w.copy(), 23, 17, 6), first)
    assert np.array_equal(partition(method, list(w), 23, 17, 6), first)


@pytest.mark.parametrize("nranks", [1, 2, 3, 4, 6, 12])
def test_strips_uniform_perfect(nranks):
    nx, ny = 12, 5
    for axis, n_lines in [(0, nx), (1, ny)]:
        owner = strips(np.ones(nx * ny), nx, ny, nranks, axis=axis)
        if n_lines % nranks == 0:
            assert imbalance(np.ones(nx * ny), owner, nranks) == 1.0
        # Whole columns (axis 0) or rows (axis 1), ranks in increasing order
        o = owner.reshape(ny, nx)
        lines = o[0, :] if axis == 0 else o[:, 0]
        assert np.all(o == (lines[None, :] if axis == 0 else lines[:, None]))
        assert np.all(np.diff(lines) >= 0)


UNIFORM = [(8, 8, 2), (8, 8, 4), (8, 8, 8), (8, 8, 16), (12, 6, 3), (12, 6, 6), (10, 3, 5)]


@pytest.mark.parametrize("nx,ny,nranks", UNIFORM + [(6, 9, 9)])
@pytest.mark.parametrize("split", ["best", "longer"])
def test_rcb_uniform_perfect(nx, ny, nranks, split):
    owner = rcb(np.ones(nx * ny), nx, ny, nranks, split=split)
    if (nx, ny, nranks) == (6, 9, 9) and split == "longer":
        # 6 x 5 with 5 ranks: 6 columns cannot split 2:3, 5 rows can ("best" does);
        # the worst rank ends with 8 cells for a mean of 6
        assert imbalance(np.ones(nx * ny), owner, nranks) == pytest.approx(8 / 6)
    else:
        assert imbalance(np.ones(nx * ny), owner, nranks) == 1.0
    # Each rank owns a rectangle of cells
    o = owner.reshape(ny, nx)
    for r in range(nranks):
        iy, ix = np.nonzero(o == r)
        assert len(ix) == (ix.max() - ix.min() + 1) * (iy.max() - iy.min() + 1)


@pytest.mark.parametrize("method", METHODS)
def test_zero_weights_balance_cells(method):
    owner = partition(method, np.zeros(48), 8, 6, 4)
    assert imbalance(np.ones(48), owner, 4) == 1.0


@pytest.mark.parametrize("nranks", [2, 3, 4])
@pytest.mark.parametrize("nx,ny", [(30, 3), (24, 12), (12, 12), (40, 20)])
def test_rcb_bed_lower_third(nx, ny, nranks):
    """A bed filling the lower third, empty above: RCB balances it, row strips cannot.

    On the 30 x 3 grid the bed is one row, so strips along y give all of it to one rank.
    """
    w = _bed(nx, ny, ny // 3, seed=nranks)
    for split in ["best", "longer"]:
        assert imbalance(w, rcb(w, nx, ny, nranks, split=split), nranks) < 1.2
    if ny == 3:
        assert imbalance(w, strips(w, nx, ny, nranks, axis=1), nranks) == nranks
    if (ny // 3) % nranks:
        assert imbalance(w, strips(w, nx, ny, nranks, axis=1), nranks) > 1.2


def test_rcb_best_split_follows_the_bed():
    """The cheaper-axis rule beats the longer-side rule on a bed in a tall box.

    The 10 x 30 box with a 5-row bed: "longer" first cuts across the bed rows.
    """
    nx, ny = 10, 30
    w = _bed(nx, ny, 5, seed=1)
    for nranks in [2, 3, 4, 8, 16]:
        best = imbalance(w, rcb(w, nx, ny, nranks, split="best"), nranks)
        longer = imbalance(w, rcb(w, nx, ny, nranks, split="longer"), nranks)
        assert best < longer
        if nranks <= 4:
            assert best < 1.25
    # 16 ranks on 50 loaded cells: granularity-limited, yet half the longer-side imbalance
    assert best < 0.6 * longer


@pytest.mark.parametrize("method", METHODS)
def test_more_ranks_than_cells(method):
    nx, ny, nranks = 2, 2, 7
    owner = partition(method, np.ones(4), nx, ny, nranks)
    assert owner.min() >= 0 and owner.max() < nranks
    if method == "rcb":
        # One cell per rank, 3 ranks idle
        assert len(np.unique(owner)) == 4
        assert owner.tolist() == [0, 3, 1, 5]
    else:
        # Two columns: two ranks busy, the others own nothing
        assert len(np.unique(owner)) == 2
    # A single cell goes to one rank (rcb: the lowest; strips: the last, ties go to empty)
    assert partition(method, np.ones(1), 1, 1, 5).tolist() == [0 if method == "rcb" else 4]


def test_strips_ranks_beyond_columns():
    owner = strips(np.ones(3), 3, 1, 5)
    assert loads(np.ones(3), owner, 5).tolist() == [1.0, 0.0, 1.0, 0.0, 1.0]


def test_cut_line_near_optimal():
    """Greedy cuts stay within one entry's weight of the optimal bottleneck."""
    rng = np.random.default_rng(7)
    for n, k in itertools.product(range(1, 10), range(1, 7)):
        w = rng.random(n) * (rng.random(n) < 0.7)
        cuts = cut_line(w, k)
        assert cuts[0] == 0 and cuts[-1] == n and np.all(np.diff(cuts) >= 0)
        prefix = np.concatenate([[0.0], np.cumsum(w)])
        bottleneck = np.max(prefix[cuts[1:]] - prefix[cuts[:-1]])
        assert bottleneck <= _optimal_bottleneck(w, k) + w.max(initial=0.0) + 1e-12
