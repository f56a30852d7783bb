"""The grains of a preparation: random ellipses in loose rows above the chamber floor.

Sizes, shapes, angles and horizontal jitter are drawn from one seeded generator
(``numpy.random.default_rng(seed)``, PCG64), so the same seed gives the same grains on any
machine and any number of ranks. Each grain sits in its own square cell of side
``1.05 * 2 a_max``, so no two grains touch when the rain starts.
"""

import numpy as np

from pdfem.errors import InputError

# Cell side over the largest grain diameter (grains start apart)
CELL = 1.05


def rain_grains(n, seed, semi_axis, aspect, x0, x1, floor, top):
    """(n, 5) rows x, y, a, b, angle of grains stacked in rows from ``floor`` upwards.

    x0, x1: chamber walls; floor: the chamber floor; top: highest y a grain may reach.
    Raises InputError (naming prepare.grains) when the chamber is too low to hold them.
    """
    rng = np.random.default_rng(seed)
    # Sizes and shapes first (one draw each), then the placement jitter
    a = rng.uniform(semi_axis[0], semi_axis[1], n)
    b = a * rng.uniform(aspect[0], aspect[1], n)
    angle = rng.uniform(0.0, np.pi, n)
    side = CELL * 2.0 * semi_axis[1]
    ncol = int((x1 - x0) // side)
    if ncol < 1:
        raise InputError(f"prepare.semi_axis: grains of semi-axis {semi_axis[1]:g} m do not fit "
                         f"between the walls ({x1 - x0:g} m apart)")
    nrow = -(-n // ncol)
    if floor + nrow * side > top:
        raise InputError(f"prepare.grains: {n} grains need {nrow} rows of {side:g} m above the "
                         f"floor at {floor:g} m, more than the domain box holds (top {top:g} m)")
    # Cell centres, row by row from the floor; jitter keeps each grain inside its cell
    k = np.arange(n)
    row, col = k // ncol, k % ncol
    spare = (x1 - x0) - ncol * side
    cx = x0 + 0.5 * spare + (col + 0.5) * side
    cy = floor + (row + 0.5) * side
    slack = 0.5 * side - a
    cx = cx + rng.uniform(-1.0, 1.0, n) * slack
    cy = cy + rng.uniform(-1.0, 1.0, n) * slack
    return np.stack([cx, cy, a, b, angle], axis=1)
