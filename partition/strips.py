"""Strip decomposition: whole columns (or rows) of cells per rank, weight-balanced."""

import numpy as np

from partition.balance import grid_weights


def cut_line(line_weights, nranks):
    """Split a sequence of weights into ``nranks`` contiguous groups of balanced sum.

    Each rank in turn takes the end index whose prefix sum is closest to its fair share of
    what is left (remaining weight / remaining ranks); ties go to the shorter group. A rank
    may get an empty group when there are fewer entries than ranks.

    Returns
    -------
    (nranks + 1,) int64
        Cut indices ``c``: rank r owns entries ``c[r] <= j < c[r+1]``; ``c[0] = 0``,
        ``c[-1] = len(line_weights)``.
    """
    # Prefix sums of the line
    w = np.asarray(line_weights, dtype=np.float64)
    prefix = np.concatenate([[0.0], np.cumsum(w)])
    n = w.size
    cuts = np.zeros(nranks + 1, dtype=np.int64)
    cuts[-1] = n
    # Greedy sweep: each rank aims at its share of the remaining weight
    for r in range(nranks - 1):
        start = cuts[r]
        target = prefix[start] + (prefix[-1] - prefix[start]) / (nranks - r)
        hi = max(int(np.searchsorted(prefix, target, side="left")), int(start))
        candidates = [c for c in (hi - 1, hi) if start <= c <= n]
        errors = [abs(prefix[c] - target) for c in candidates]
        cuts[r + 1] = candidates[int(np.argmin(errors))]
    return cuts


def strips(weights, nx, ny, nranks, axis=0):
    """Assign whole cell columns (``axis=0``, cuts are vertical lines) or rows (``axis=1``).

    Parameters
    ----------
    weights : (nx * ny,) array
        Non-negative cell weights (e.g. node counts), cell id ``ix + nx * iy``. All-zero
        weights balance the number of cells instead.
    nx, ny : int
        Grid size in cells.
    nranks : int
        Number of ranks; ranks beyond the number of columns (rows) own nothing.
    axis : {0, 1}
        0: strips of columns side by side along x; 1: strips of rows stacked along y.

    Returns
    -------
    owner : (nx * ny,) int32
        Rank owning each cell.
    """
    # Weight of each column (axis 0) or row (axis 1)
    w = grid_weights(weights, nx, ny, nranks)
    if axis not in (0, 1):
        raise ValueError(f"axis must be 0 or 1, got {axis!r}")
    line = w.sum(axis=0) if axis == 0 else w.sum(axis=1)
    # Cut the line, then give each cell the owner of its column or row
    cuts = cut_line(line, int(nranks))
    line_owner = np.searchsorted(cuts, np.arange(line.size), side="right") - 1
    owner = line_owner[None, :] if axis == 0 else line_owner[:, None]
    return np.broadcast_to(owner, (ny, nx)).ravel().astype(np.int32)
