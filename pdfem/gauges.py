"""Gauges: time histories of the mean velocity and stress of a set of elements, and of the
contact force on their nodes.

A gauge is a set of elements of one body: a block's elements along one side (the hammer's
bottom row, the chamber bottom's top row, the report's fig. 12), one element of a block, or
the element that contains a given point at t = 0. The element sets are fixed when the run
starts and kept in its checkpoints (:meth:`Gauges.packed`), so a restart on any number of
ranks samples the same elements, even where a point gauge's point has since left them. Each
sample is the area-weighted mean over the gauge's elements of the element velocity (mean of
its four nodes) and of the Cauchy stress (mean over its integration points; xx, yy, xy, zz,
tension positive), and the sum over the gauge elements' nodes of the contact forces [N/m]
(what the bed pushes on a hammer's bottom row: a rigid, driven piston has no strain and so no
stress to read). Only the rank that owns the body contributes (rank 0 for blocks), so a
sample is the same on any rank count.
"""

import numpy as np

from pdfem.errors import InputError
from pdfem.parallel.mpi import allgather_objects, array_sum

# Columns of one sample: velocity (2), stress (4), contact force (2)
NCOL = 8


def block_elements(nx, ny, side):
    """Element indices (i + nx j) of a block meshed nx by ny along ``side`` (or all)."""
    ids = np.arange(nx * ny, dtype=np.int64).reshape(ny, nx)
    sel = {"bottom": ids[0, :], "top": ids[-1, :], "left": ids[:, 0], "right": ids[:, -1],
           "all": ids.ravel()}
    return np.sort(sel[side])


def _quad_contains(xe, p):
    """True when point p lies in (or on) the counter-clockwise quad xe (4, 2)."""
    for k in range(4):
        a, b = xe[k], xe[(k + 1) % 4]
        if (b[0] - a[0]) * (p[1] - a[1]) - (b[1] - a[1]) * (p[0] - a[0]) < 0.0:
            return False
    return True


def _locate(st, ctx, point, where):
    """(body gid, local element) of the element holding ``point`` at t = 0, any rank."""
    s, comm = st.store, ctx.comm
    found = (np.iinfo(np.int64).max, -1)
    p = np.asarray(point, float)
    for b in range(s.nb_own):
        if s.isglobal[b] and comm.rank != 0:
            continue
        e0 = s.estart[b]
        for le in range(s.ne[b]):
            if _quad_contains(s.x[s.conn[e0 + le]], p):
                found = min(found, (int(s.gid[b]), le))
                break
    best = min(allgather_objects(comm, found))
    if best[1] < 0:
        raise InputError(f"{where}.point: no element contains {list(point)} at t=0")
    return best


def unpack_sets(flat, count, where):
    """Element sets from :meth:`Gauges.packed`: ``count`` pairs (body gid, element indices);
    InputError naming ``where`` when the array does not hold them."""
    sets, k = [], 0
    flat = np.asarray(flat, np.float64).ravel()
    try:
        for _ in range(count):
            gid, n = int(flat[k]), int(flat[k + 1])
            elems = flat[k + 2:k + 2 + n]
            if n < 1 or elems.size != n or np.any(elems < 0) or np.any(elems != np.floor(elems)):
                raise ValueError
            sets.append((gid, elems.astype(np.int64)))
            k += 2 + n
    except (IndexError, ValueError, OverflowError):
        raise InputError(f"{where}: gauge_sets does not hold the scene's {count} gauges") from None
    if k != flat.size:
        raise InputError(f"{where}: gauge_sets does not hold the scene's {count} gauges")
    return sets


class Gauges:
    """The gauges of a run: element sets, and the samples gathered on rank 0.

    ``saved``: the packed element sets of a checkpoint (a restart; ``where`` names it in an
    error); otherwise they are found from the scene in the current (initial) state."""

    def __init__(self, st, ctx, saved=None, where=None):
        r = ctx.resolved
        self.names = [g["name"] for g in r.get("gauges", [])]
        self.times, self.rows = [], []
        if saved is not None:
            self.sets = unpack_sets(saved, len(self.names), where)
            return
        self.sets = []
        for i, g in enumerate(r.get("gauges", [])):
            if "body" in g:
                blk = r["blocks"][ctx.blocks.index(g["body"])]
                elems = (np.array([g["element"]], np.int64) if "element" in g else
                         block_elements(blk["nx"], blk["ny"], g["side"]))
                gid = ctx.blocks.gid(g["body"])
            else:
                gid, le = _locate(st, ctx, g["point"], f"{ctx.scene.name}: gauges[{i}]")
                elems = np.array([le], np.int64)
            self.sets.append((gid, elems))

    def __len__(self):
        return len(self.names)

    def packed(self):
        """The element sets as one float array (gid, count, elements... per gauge), for a
        checkpoint."""
        parts = [np.concatenate([[gid, e.size], e]) for gid, e in self.sets]
        return np.concatenate(parts).astype(np.float64) if parts else np.zeros(0)

    def values(self, st, ctx):
        """(ngauge, NCOL) means at the current state, on every rank (collective)."""
        s, comm = st.store, ctx.comm
        acc = np.zeros((len(self.names), NCOL + 1))
        own = s.gid[: s.nb_own]
        for i, (gid, elems) in enumerate(self.sets):
            hit = np.nonzero(own == gid)[0]
            if hit.size == 0 or (s.isglobal[hit[0]] and comm.rank != 0):
                continue
            e = s.estart[hit[0]] + elems
            xe, ve = s.x[s.conn[e]], s.v[s.conn[e]]
            # Element areas (shoelace) weight the element means
            area = 0.5 * ((xe[:, 2, 0] - xe[:, 0, 0]) * (xe[:, 3, 1] - xe[:, 1, 1])
                          - (xe[:, 3, 0] - xe[:, 1, 0]) * (xe[:, 2, 1] - xe[:, 0, 1]))
            acc[i, 0] = area.sum()
            acc[i, 1:3] = (area[:, None] * ve.mean(axis=1)).sum(axis=0)
            acc[i, 3:7] = (area[:, None] * s.sig[e].mean(axis=1)).sum(axis=0)
            if st.fc.shape[0]:
                acc[i, 7:] = st.fc[np.unique(s.conn[e])].sum(axis=0)
        array_sum(comm, acc)
        # Area-weighted means of velocity and stress; the force is a sum
        means = acc[:, 1:7] / np.where(acc[:, :1] > 0.0, acc[:, :1], 1.0)
        return np.concatenate([means, acc[:, 7:]], axis=1)

    def sample(self, st, ctx):
        """Record one sample (collective; rank 0 keeps the history)."""
        vals = self.values(st, ctx)
        if ctx.comm.rank == 0:
            self.times.append(st.t)
            self.rows.append(vals)

    def history(self):
        """(times (G,), values (G, ngauge, NCOL)) on rank 0."""
        n = len(self.names)
        return (np.array(self.times), np.array(self.rows).reshape(len(self.times), n, NCOL))
