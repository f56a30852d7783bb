"""Redistribute rows keyed by a global index to contiguous blocks, one block per rank.

Parallel HDF5 writes are fastest as one contiguous slab per rank. Rows (nodes, elements)
of owned bodies are scattered over the global numbering, so each rank sends every row to
the rank whose block holds its index; each rank then writes [lo, hi) in one call.
"""

import numpy as np

from pdfem.parallel.mpi import alltoallv


def block_bounds(n, size, rank):
    """[lo, hi) of rank's block of an index range of length n."""
    return n * rank // size, n * (rank + 1) // size


def block_owner(index, n, size):
    """The rank whose block of [0, n) (:func:`block_bounds`) holds each global index."""
    lo_of = np.array([block_bounds(n, size, r)[0] for r in range(size)])
    return np.searchsorted(lo_of, index, side="right") - 1


def to_blocks(comm, index, rows, n):
    """Send rows (m, k) with global indices (m,) to their block owners.

    Returns (lo, hi, block) with block (hi - lo, k) in index order. Every index in [0, n)
    must be supplied by exactly one rank.
    """
    size, rank = comm.size, comm.rank
    rows = np.ascontiguousarray(rows, np.float64)
    # Columns per row from the trailing shape (a rank with no rows still knows it)
    k = int(np.prod(rows.shape[1:], dtype=np.int64)) if rows.ndim > 1 else 1
    rows = rows.reshape(index.shape[0], k)
    dest = block_owner(index, n, size)
    order = np.argsort(dest, kind="stable")
    bufs = []
    for r in range(size):
        sel = order[dest[order] == r]
        bufs.append(np.concatenate([index[sel].astype(np.float64)[:, None], rows[sel]],
                                   axis=1).ravel())
    got = np.concatenate([b.reshape(-1, k + 1) for b in alltoallv(comm, bufs)])
    lo, hi = block_bounds(n, size, rank)
    idx = got[:, 0].astype(np.int64)
    if idx.shape[0] != hi - lo or (idx.shape[0] and not np.array_equal(np.sort(idx),
                                                                        np.arange(lo, hi))):
        raise RuntimeError("output rows do not cover the global numbering exactly once")
    block = np.empty((hi - lo, k))
    block[idx - lo] = got[:, 1:]
    return lo, hi, block
