"""Structured quad mesh of an axis-aligned rectangle (walls, pistons, rectangular grains)."""

import numpy as np


def block_mesh(x0, y0, x1, y1, nx=3, ny=1):
    """Mesh the rectangle ``[x0, x1] x [y0, y1]`` [m] with ``nx x ny`` equal quads.

    Node ``(i, j)`` (column i = 0..nx, row j = 0..ny) has index ``i + (nx + 1) j``.

    Returns
    -------
    xy : (nn, 2) float64
        Node coordinates, ``nn = (nx + 1)(ny + 1)``.
    conn : (nx ny, 4) int64
        Counter-clockwise connectivity, element ``(i, j)`` at index ``i + nx j``.
    boundary : (2 (nx + ny),) int64
        Closed counter-clockwise loop of boundary nodes starting at corner ``(x0, y0)``.
    node_sets : dict[str, ndarray]
        Sorted int64 node indices for ``'left'``, ``'right'``, ``'bottom'``, ``'top'`` (each
        corner in both adjacent sets) and ``'all'``.
    """
    # Validate arguments
    nx, ny = int(nx), int(ny)
    if nx < 1 or ny < 1:
        raise ValueError(f"nx and ny must be >= 1, got nx={nx}, ny={ny}")
    if not (x1 > x0 and y1 > y0):
        raise ValueError(f"empty rectangle [{x0}, {x1}] x [{y0}, {y1}]")
    # Node grid; end coordinates set exactly
    xs = np.linspace(x0, x1, nx + 1)
    ys = np.linspace(y0, y1, ny + 1)
    gx, gy = np.meshgrid(xs, ys, indexing="xy")
    xy = np.stack([gx.ravel(), gy.ravel()], axis=1).astype(np.float64)
    ids = np.arange((nx + 1) * (ny + 1), dtype=np.int64).reshape(ny + 1, nx + 1)
    # Elements (i, j): nodes (i, j), (i+1, j), (i+1, j+1), (i, j+1)
    corners = [ids[:-1, :-1], ids[:-1, 1:], ids[1:, 1:], ids[1:, :-1]]
    conn = np.stack(corners, axis=-1).reshape(-1, 4)
    # Boundary loop: bottom left->right, right up, top right->left, left down
    boundary = np.concatenate([ids[0, :-1], ids[:-1, -1], ids[-1, :0:-1], ids[:0:-1, 0]])
    # Named node sets
    node_sets = {
        "left": np.sort(ids[:, 0]),
        "right": np.sort(ids[:, -1]),
        "bottom": np.sort(ids[0, :]),
        "top": np.sort(ids[-1, :]),
        "all": ids.ravel().copy(),
    }
    return xy, conn.astype(np.int64), boundary.astype(np.int64), node_sets
