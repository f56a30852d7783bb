"""A cell list of points: counting sort into an nx by ny grid of square cells, and the 3 x 3
block of cells around one. Point i is in cell ``cell[i]`` = ix ny + iy; the points of cell k
are ``items[start[k]:start[k+1]]``.
"""

from numba import njit


@njit(cache=True)
def build_cells(cx, cy, x0, y0, h, nx, ny, cell, start, items):
    """Counting sort of the grains into the cell grid (fills cell, start (ncell+1), items)."""
    n = cx.shape[0]
    start[:] = 0
    for i in range(n):
        ix = min(max(int((cx[i] - x0) / h), 0), nx - 1)
        iy = min(max(int((cy[i] - y0) / h), 0), ny - 1)
        cell[i] = ix * ny + iy
        start[cell[i] + 1] += 1
    for k in range(nx * ny):
        start[k + 1] += start[k]
    fill = start[:-1].copy()
    for i in range(n):
        items[fill[cell[i]]] = i
        fill[cell[i]] += 1


@njit(cache=True)
def around(c, nx, ny, out):
    """The cells of the 3 x 3 block around cell c (within the grid) into out; their count."""
    ix, iy = c // ny, c % ny
    n = 0
    for ax in range(max(ix - 1, 0), min(ix + 2, nx)):
        for ay in range(max(iy - 1, 0), min(iy + 2, ny)):
            out[n] = ax * ny + ay
            n += 1
    return n
