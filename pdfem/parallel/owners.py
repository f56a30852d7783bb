"""Cell owners: the partition of the contact cell grid among the ranks (the domain
decomposition), and the cell weights it balances.

Every partition of a run asks here: at set-up (the scene's grains, known to every rank), at a
restart (the checkpoint's grains, each rank holding a share) and at a rebalance (the owned
grains' element counts). Weights are integers summed exactly over the ranks, so every rank
computes the same owners, whatever the rank count and the order of the sums.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

import numpy as np

from partition import partition
from pdfem.parallel.exchange import owned_grain_cells
from pdfem.parallel.mpi import global_sum_exact

if TYPE_CHECKING:
    from partition import CellGrid
    from pdfem.store import Store


def cell_owners(method: str, weights: np.ndarray, grid: CellGrid, nranks: int) -> np.ndarray:
    """Owner rank of each cell of ``grid`` by the partition ``method`` (domain.partition)
    for the float ``weights`` of the cells."""
    return partition(method, weights, grid.nx, grid.ny, nranks)


def owned_cell_weights(comm: Any, store: Store, grid: CellGrid, nglobal: int,
                       per_grain: np.ndarray | None = None) -> np.ndarray:
    """The weight of each cell over every rank (collective): the number of grains whose
    centroid lies in it, or the sum of ``per_grain`` (an integer per owned grain, local
    bodies [nglobal, nb_own)) over them; exact, as floats."""
    cells = owned_grain_cells(store, grid, nglobal)
    w = np.bincount(cells, weights=per_grain, minlength=grid.ncell).astype(np.int64)
    return global_sum_exact(comm, w).astype(float)
