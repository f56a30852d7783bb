"""Migration and ghost lists (the per-step halo refresh is :mod:`pdfem.parallel.halo`).

A rebuild runs in two phases. Phase A sends every owned grain whose centroid lies in a cell
of another rank to that rank, with all of its state and its contact history. Phase B sends
a copy of every owned grain to each rank owning a cell of its cell neighbourhood: those
copies are the ghosts. The neighbourhood is the (2 r + 1)^2 block of cells around the
grain's, r the reach (:func:`cell_reach`): 1 (the 3x3 block) while the grains are no larger
than the cell size allows, more once they have grown (flattened grains of a compacted bed).
Between rebuilds only node positions and velocities (and the fields effects register) of
ghosts are refreshed, from owner to ghost, every step.
"""

import math

import numpy as np

from pdfem.kernels.centroids import body_centroids
from pdfem.parallel.halo import Halo
from pdfem.parallel.mpi import alltoallv, array_max
from pdfem.store import Batch, Store, ranges


def owned_grain_cells(store, grid, nglobal):
    """Cell of the centroid of each owned grain (local bodies [nglobal, nb_own))."""
    n = store.nb_own - nglobal
    cent = np.empty((n, 2))
    body_centroids(store.x, store.nstart, store.nn, nglobal, store.nb_own, cent)
    return grid.cell_of(cent)


def cell_reach(comm, store, grid, nglobal, skin):
    """Cells apart (in x and in y) that two grains within ``skin`` of each other can have
    their centroids, at most, over every rank (collective): two boxes within skin have
    centroids at most D_i + D_j + skin apart per axis, D the distance from a grain's centroid
    to the farthest side of its box, and points that far apart lie at most
    ceil(distance / cell width) cells apart. At least 1, at most the grid's larger side (a
    reach that wide already covers every cell: a grain torn across the box by a run that the
    guards are about to stop must not size arrays beyond memory). Returns (reach, wide), wide
    the widest grain's extent in x [m] (periodic sides: grains that may touch are at most
    wide + skin apart, centre to centre of their boxes)."""
    n = store.nb_own - nglobal
    far = wide = 0.0
    if n:
        cent = np.empty((n, 2))
        body_centroids(store.x, store.nstart, store.nn, nglobal, store.nb_own, cent)
        first = store.nstart[nglobal:store.nb_own]
        x = store.x[: store.nn_own]
        lo = np.minimum.reduceat(x, first, axis=0)
        hi = np.maximum.reduceat(x, first, axis=0)
        far_x = np.maximum(cent[:, 0] - lo[:, 0], hi[:, 0] - cent[:, 0]).max() / grid.hx
        far_y = np.maximum(cent[:, 1] - lo[:, 1], hi[:, 1] - cent[:, 1]).max() / grid.hy
        far = max(far_x, far_y)
        wide = float((hi[:, 0] - lo[:, 0]).max())
    skin_cells = skin / min(grid.hx, grid.hy)
    far, wide = array_max(comm, np.array([far, wide]))
    reach = 2.0 * far + skin_cells
    widest = max(grid.nx, grid.ny)
    return (max(1, math.ceil(reach)) if reach < widest else widest), float(wide)


def neighbour_ranks(grid, owner, cells, reach=1):
    """(n, (2 reach + 1)^2) ranks owning the cell block of ``reach`` cells around each cell
    (clipped at the grid edge; wrapped in x when the grid is periodic there, so that a grain
    near one side is a ghost, as it is, on the ranks owning cells near the other)."""
    ix, iy = cells % grid.nx, cells // grid.nx
    side = 2 * reach + 1
    out = np.empty((cells.shape[0], side * side), np.int64)
    k = 0
    for dy in range(-reach, reach + 1):
        for dx in range(-reach, reach + 1):
            jx = (np.mod(ix + dx, grid.nx) if grid.periodic_x
                  else np.clip(ix + dx, 0, grid.nx - 1))
            jy = np.clip(iy + dy, 0, grid.ny - 1)
            out[:, k] = owner[jx + grid.nx * jy]
            k += 1
    return out


def _history_rows(batches, fields, keep_gids, global_gids):
    """Unique history rows (by key) that involve a kept grain, or only global bodies and
    walls (a block against a block or a wall: every rank keeps those)."""
    keys = np.concatenate([b.a["hkey"] for b in batches])
    vals = np.concatenate([b.a["hval"] for b in batches])
    if keys.shape[0] == 0:
        return keys, vals
    keys, first = np.unique(keys, axis=0, return_index=True)
    vals = vals[first]
    a, b = keys[:, 0], keys[:, 2]
    mine = np.isin(a, keep_gids) | np.isin(b, keep_gids)
    both_global = np.isin(a, global_gids) & (np.isin(b, global_gids) | (b < 0))
    sel = mine | both_global
    return keys[sel], vals[sel]


def rebuild(comm, store, grid, owner, nglobal, reach=1):
    """Migrate grains to the owners of their cells and rebuild the ghosts of the cell
    neighbourhoods of ``reach`` cells.

    Returns the new :class:`Store` and its :class:`Halo`. The first ``nglobal`` local bodies
    are the global bodies, identical on every rank; they are neither migrated nor ghosted.
    """
    fields, rank, size = store.fields, comm.rank, comm.size

    # Phase A: owned grains go to the owner of their centroid cell, with their history
    cells = owned_grain_cells(store, grid, nglobal)
    dest = owner[cells]
    local = np.arange(nglobal, store.nb_own)
    bufs = [store.take(local[dest == r]).to_buffer() if r != rank else np.zeros(0)
            for r in range(size)]
    stay = store.take(local[dest == rank])
    got = [Batch.from_buffer(fields, b)[0] for r, b in enumerate(alltoallv(comm, bufs))
           if r != rank and b.size]
    owned = Batch.concat(fields, [stay] + got)
    order = np.argsort(owned.a["gid"], kind="stable")
    glob = store.take(np.arange(nglobal), with_history=False)
    global_gids = glob.a["gid"]
    hist_src = [stay] + got + [store.take(np.arange(nglobal))]
    hkeys, hvals = _history_rows(hist_src, fields, owned.a["gid"], global_gids)
    owned_tmp = Store(fields, Batch.concat(fields, [glob, owned]), nglobal + owned.nbody)
    sorted_owned = owned_tmp.take(nglobal + order, with_history=False)
    sorted_owned.a["hkey"], sorted_owned.a["hval"] = hkeys, hvals

    # Phase B: ghosts for every rank owning a cell next to an owned grain's cell
    base = Store(fields, Batch.concat(fields, [glob, sorted_owned]), nglobal + owned.nbody)
    cells = owned_grain_cells(base, grid, nglobal)
    nbr = neighbour_ranks(grid, owner, cells, reach)
    send_bodies = {}
    bufs = []
    for r in range(size):
        sel = np.nonzero((nbr == r).any(axis=1))[0] + nglobal if r != rank else []
        if len(sel):
            send_bodies[r] = np.asarray(sel, np.int64)
            bufs.append(base.take(send_bodies[r], with_history=False).to_buffer())
        else:
            bufs.append(np.zeros(0))
    ghosts, sources = [], []
    for r, b in enumerate(alltoallv(comm, bufs)):
        if r != rank and b.size:
            ghosts.append(Batch.from_buffer(fields, b)[0])
            sources.append(r)

    # Assemble: globals, owned (by gid), ghosts (by source rank, then gid as sent)
    new = Store(fields, Batch.concat(fields, [glob, sorted_owned] + ghosts), base.nb_own)
    send = {r: ranges(new.nstart[bs], new.nn[bs]) for r, bs in send_bodies.items()}
    recv, n0 = {}, new.nn_own
    for r, g in zip(sources, ghosts, strict=True):
        cnt = int(g.a["nn"].sum())
        recv[r] = (n0, cnt)
        n0 += cnt
    return new, Halo(comm, send, recv)
