"""Domain decomposition of the contact cell grid (pure numpy, no MPI).

The uniform contact-detection grid (:class:`CellGrid`) is also the decomposition: each cell
is owned by one rank. :func:`strips` and :func:`rcb` compute the owner of every cell from
per-cell weights; :mod:`partition.balance` measures the result.
"""

from partition.balance import grid_weights, imbalance, loads, needs_rebalance
from partition.grid import CellGrid
from partition.rcb import rcb
from partition.strips import strips

__all__ = [
    "CellGrid",
    "grid_weights",
    "imbalance",
    "loads",
    "needs_rebalance",
    "partition",
    "rcb",
    "strips",
]

METHODS = {"strips": strips, "rcb": rcb}


def partition(method, weights, nx, ny, nranks, **options):
    """Owner rank (int32, shape (nx * ny,)) of every cell by ``method`` ('strips' or 'rcb').

    Extra keyword ``options`` go to the method (e.g. ``axis=1`` for strips).
    """
    # Look the method up by name
    try:
        func = METHODS[method]
    except (KeyError, TypeError):
        raise ValueError(
            f"unknown partition method {method!r}; expected one of {sorted(METHODS)}"
        ) from None
    return func(weights, nx, ny, nranks, **options)
