"""Load balance measures of a cell-to-rank assignment."""

import numpy as np


def loads(weights, owner, nranks):
    """Summed cell weights per rank, float64 shape (nranks,)."""
    # Weighted histogram of the owners
    owner = np.asarray(owner, dtype=np.int64).ravel()
    weights = np.asarray(weights, dtype=np.float64).ravel()
    if owner.shape != weights.shape:
        raise ValueError(f"weights {weights.shape} and owner {owner.shape} differ in shape")
    if owner.size and (owner.min() < 0 or owner.max() >= nranks):
        raise ValueError(f"owner outside [0, {nranks})")
    return np.bincount(owner, weights=weights, minlength=nranks).astype(np.float64)


def imbalance(weights, owner, nranks):
    """Max rank load over mean rank load (1.0 is perfect; 1.0 when all weights are zero)."""
    # Ratio of the largest load to the mean
    load = loads(weights, owner, nranks)
    mean = load.sum() / nranks
    if mean <= 0.0:
        return 1.0
    return float(load.max() / mean)


def needs_rebalance(weights, owner, nranks, threshold):
    """True when ``imbalance(weights, owner, nranks)`` exceeds ``threshold`` (e.g. 1.1)."""
    return imbalance(weights, owner, nranks) > threshold


def grid_weights(weights, nx, ny, nranks):
    """Validate partition inputs; return the weights as a float64 (ny, nx) array.

    Weights must be finite and non-negative. When they are all zero, every cell counts 1,
    so the partition falls back to balancing the number of cells.
    """
    # Shapes and counts
    if int(nranks) < 1:
        raise ValueError(f"nranks must be >= 1, got {nranks!r}")
    if int(nx) < 1 or int(ny) < 1:
        raise ValueError(f"grid must have nx, ny >= 1, got nx={nx!r}, ny={ny!r}")
    w = np.asarray(weights, dtype=np.float64).ravel()
    if w.size != nx * ny:
        raise ValueError(f"expected {nx * ny} cell weights (nx={nx}, ny={ny}), got {w.size}")
    # Values
    if not np.all(np.isfinite(w)) or np.any(w < 0.0):
        raise ValueError("cell weights must be finite and non-negative")
    if not np.any(w > 0.0):
        w = np.ones_like(w)
    return w.reshape(ny, nx)
