"""Uniform cell grid over the domain box: contact-detection bins and decomposition units.

Cell ``(ix, iy)`` has id ``ix + nx * iy``. Cells are at least ``cell_size`` wide, so two
bodies closer than ``cell_size`` always lie in the same or in 8-neighbouring cells. With
periodic x the columns close on themselves: column ``nx - 1`` neighbours column 0, and a point
beyond a side belongs to the cell of its image inside the box.
"""

import math

import numpy as np


class CellGrid:
    """Uniform grid of ``nx x ny`` cells covering ``box = (xmin, ymin, xmax, ymax)`` [m].

    ``nx = max(1, floor(width / cell_size))`` (likewise ``ny``), so the actual cell widths
    ``hx = width / nx`` and ``hy = height / ny`` are never below ``cell_size``.
    """

    def __init__(self, box, cell_size, periodic_x=False):
        # Validate and store the box
        xmin, ymin, xmax, ymax = (float(v) for v in box)
        if not (xmax > xmin and ymax > ymin):
            raise ValueError(f"empty box {box!r}")
        if not cell_size > 0.0:
            raise ValueError(f"cell_size must be positive, got {cell_size!r}")
        self.box = (xmin, ymin, xmax, ymax)
        self.cell_size = float(cell_size)
        # Whole cells at least cell_size wide
        self.nx = max(1, math.floor((xmax - xmin) / cell_size))
        self.ny = max(1, math.floor((ymax - ymin) / cell_size))
        self.hx = (xmax - xmin) / self.nx
        self.hy = (ymax - ymin) / self.ny
        self.ncell = self.nx * self.ny
        # The period in x [m] (0 when the sides are not periodic)
        self.periodic_x = bool(periodic_x)
        self.period = xmax - xmin if periodic_x else 0.0

    def __repr__(self):
        size = f"cell_size={self.cell_size!r}, nx={self.nx}, ny={self.ny}"
        periodic = ", periodic_x=True" if self.periodic_x else ""
        return f"CellGrid(box={self.box!r}, {size}{periodic})"

    def cell_of(self, points):
        """Cell id (int64, shape (n,)) of each point of ``points`` (n, 2).

        Points outside the box are clamped to the border cells; with periodic x a point beyond
        a side takes the column of its image (the column index modulo nx).
        """
        # Column and row indices, clamped to the grid (wrapped in x when periodic)
        p = np.asarray(points, dtype=np.float64).reshape(-1, 2)
        ix = np.floor((p[:, 0] - self.box[0]) / self.hx)
        iy = np.floor((p[:, 1] - self.box[1]) / self.hy)
        if self.periodic_x:
            ix = np.mod(ix, self.nx).astype(np.int64)
        else:
            ix = np.clip(ix, 0, self.nx - 1).astype(np.int64)
        iy = np.clip(iy, 0, self.ny - 1).astype(np.int64)
        return ix + self.nx * iy

    def neighbours(self, cell):
        """Sorted int64 ids of the up-to-9 cells of the 3x3 block around ``cell`` (itself too)."""
        # Clipped index ranges around the cell
        cell = self._check(cell)
        ix, iy = cell % self.nx, cell // self.nx
        xs = np.arange(max(ix - 1, 0), min(ix + 2, self.nx), dtype=np.int64)
        ys = np.arange(max(iy - 1, 0), min(iy + 2, self.ny), dtype=np.int64)
        return (xs[None, :] + self.nx * ys[:, None]).ravel()

    def ring(self, cells):
        """Sorted int64 ids of the cells 8-adjacent to the set ``cells`` but not in it."""
        # Mark the set, dilate by one cell in all 8 directions, remove the set
        cells = np.unique(np.asarray(cells, dtype=np.int64).ravel())
        if cells.size:
            self._check(cells.min())
            self._check(cells.max())
        inside = np.zeros((self.ny, self.nx), dtype=bool)
        inside.flat[cells] = True
        padded = np.pad(inside, 1)
        grown = np.zeros_like(inside)
        for dy in (0, 1, 2):
            for dx in (0, 1, 2):
                grown |= padded[dy : dy + self.ny, dx : dx + self.nx]
        return np.flatnonzero(grown & ~inside).astype(np.int64)

    def centres(self):
        """Centre coordinates [m] of all cells, shape (ncell, 2), in cell-id order."""
        # Row-major over iy then ix, matching id = ix + nx * iy
        xc = self.box[0] + (np.arange(self.nx) + 0.5) * self.hx
        yc = self.box[1] + (np.arange(self.ny) + 0.5) * self.hy
        gx, gy = np.meshgrid(xc, yc, indexing="xy")
        return np.stack([gx.ravel(), gy.ravel()], axis=1)

    def _check(self, cell):
        """Return ``cell`` as an int after checking it is a valid id."""
        cell = int(cell)
        if not 0 <= cell < self.ncell:
            raise ValueError(f"cell {cell} outside [0, {self.ncell})")
        return cell
