"""Recursive coordinate bisection of the cell grid along cell boundaries."""

import numpy as np

from partition.balance import grid_weights

# Relative cost difference below which the two axes count as equally good (rounding)
_RTOL = 1e-9


def _split_cost(line, n_low, n_high):
    """``max(W_low / n_low, W_high / n_high)`` for every interior cut 1..len(line)-1."""
    # Per-rank load on each side of each cut
    prefix = np.cumsum(line)
    low = prefix[:-1]
    return np.maximum(low / n_low, (prefix[-1] - low) / n_high)


def _best_cut(line, n_low, n_high):
    """Cut index 1..len(line)-1 minimising the larger per-rank load, and that load.

    Ties (e.g. runs of empty cells) go to the cut nearest the proportional geometric
    position ``len(line) * n_low / (n_low + n_high)``, then to the lower index.
    """
    # Exact minimisers, then the one closest to the geometric split
    cost = _split_cost(line, n_low, n_high)
    best = cost.min()
    cuts = np.flatnonzero(cost == best) + 1
    ideal = line.size * n_low / (n_low + n_high)
    return int(cuts[np.argmin(np.abs(cuts - ideal))]), float(best)


def rcb(weights, nx, ny, nranks, split="best"):
    """Recursive coordinate bisection of an ``nx x ny`` cell grid into ``nranks`` parts.

    Each box of cells is cut at a cell boundary, with ``floor(n/2)`` ranks on the low side
    and ``ceil(n/2)`` on the high side; the cut minimises the larger per-rank load of the two
    sides. Both sides always keep at least one cell; a single cell with several ranks goes to
    the lowest of them, the other ranks own nothing (possible when ``nranks > nx * ny``).

    Parameters
    ----------
    weights : (nx * ny,) array
        Non-negative cell weights, cell id ``ix + nx * iy``. All-zero weights balance the
        number of cells instead.
    nx, ny : int
        Grid size in cells.
    nranks : int
        Number of ranks.
    split : {"best", "longer"}
        Axis of each cut. "longer": the longer side of the box in cells (x on a tie).
        "best": the axis whose best cut has the lower per-rank load, the longer side on a
        tie; it follows the loaded region (e.g. a bed filling the bottom of a tall box).

    Returns
    -------
    owner : (nx * ny,) int32
        Rank owning each cell; the result depends only on the inputs (deterministic).
    """
    # Weights as a (ny, nx) array and the owner map to fill
    if split not in ("best", "longer"):
        raise ValueError(f"split must be 'best' or 'longer', got {split!r}")
    w = grid_weights(weights, nx, ny, nranks)
    owner = np.zeros((ny, nx), dtype=np.int32)
    # Work list of boxes [x0, x1) x [y0, y1) with their rank range [r0, r0 + nr)
    stack = [(0, int(nx), 0, int(ny), 0, int(nranks))]
    while stack:
        x0, x1, y0, y1, r0, nr = stack.pop()
        lx, ly = x1 - x0, y1 - y0
        # Leaf: one rank, or a single cell that cannot be split
        if nr == 1 or lx * ly == 1:
            owner[y0:y1, x0:x1] = r0
            continue
        n_low = nr // 2
        n_high = nr - n_low
        sub = w[y0:y1, x0:x1]
        # Best cut along each splittable axis
        cut_x, cost_x = _best_cut(sub.sum(axis=0), n_low, n_high) if lx > 1 else (0, np.inf)
        cut_y, cost_y = _best_cut(sub.sum(axis=1), n_low, n_high) if ly > 1 else (0, np.inf)
        # Axis: the longer side (x on a tie), or with split="best" the clearly cheaper cut
        along_x = lx >= ly if ly > 1 else True
        both = lx > 1 and ly > 1
        if split == "best" and both and abs(cost_x - cost_y) > _RTOL * max(cost_x, cost_y):
            along_x = cost_x < cost_y
        if along_x:
            cut = x0 + cut_x
            stack.append((x0, cut, y0, y1, r0, n_low))
            stack.append((cut, x1, y0, y1, r0 + n_low, n_high))
        else:
            cut = y0 + cut_y
            stack.append((x0, x1, y0, cut, r0, n_low))
            stack.append((x0, x1, cut, y1, r0 + n_low, n_high))
    return owner.ravel()
