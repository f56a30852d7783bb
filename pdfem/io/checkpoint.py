"""Checkpoints: everything a run needs to continue, written by every rank into one HDF5 file.

Layout (by global id, like the run file, so that a checkpoint written on any number of ranks
is the same file):
    /bodies/<field> (NB, ...)     the body fields of every body (gid, nn, ne, ...), row = gid
    /nodes/<field> (NN, ...)      node fields by the global node numbering
                                  (:class:`pdfem.build.Layout`); with contact also
                                  /nodes/contact_force, the forces of the last step
    /elems/<field> (NE, ...)      element fields by the global element numbering
    /history/key (H, 4) int64, /history/value (H,), /history/start (NB + 1,)
                                  the contact history by body: body b's rows are
                                  start[b]:start[b+1], sorted by key; a row between two
                                  grains is stored under each of them
    /driver/<name>                the driver's series (energy, gauges; rank 0 holds them)
    attributes: format, pdfem_version, scene (TOML), fields, nranks, state (JSON: time,
    step, time steps, output schedules, frame segments)
There is no random state to save: runs draw no random numbers after set-up.

Writing (:func:`write_checkpoint`, collective): every rank sends its owned rows to the rank
whose block of the numbering holds them (:func:`pdfem.io.gather.to_blocks`), and every rank
writes its block into ``<path>.part`` through h5py's mpio driver; no rank ever holds more
than its share. Once the file is closed, rank 0 renames it over ``<path>``, so a process
killed at any moment leaves the previous checkpoint or the new one, never a torn file.

Reading (:func:`read_checkpoint`, collective, any number of ranks): every rank reads the
global bodies and one contiguous block of grains by gid, with their contact history; the
solver then moves the grains to the owners of their cells (:func:`pdfem.parallel.exchange.
rebuild`). The result is bit-identical to the run that never stopped.
"""

import json
import os
import tomllib

import h5py
import numpy as np
from mpi4py import MPI

from pdfem import __version__
from pdfem.errors import InputError
from pdfem.io.gather import block_bounds, block_owner, to_blocks
from pdfem.parallel.mpi import alltoallv
from pdfem.store import BODY, ELEM, NODE, Batch, ranges

FORMAT = 3
# Group of each field kind
GROUPS = {BODY: "bodies", NODE: "nodes", ELEM: "elems"}
# The state entries every checkpoint holds (numbers), and the driver arrays
STATE_KEYS = ("t", "nstep", "dt", "dt_prev", "nframe", "frames_k", "samples_k", "gauges_k",
              "checkpoint_k")
ARRAY_KEYS = ("energy_rows", "energy_ref")
# Fields of earlier versions that no run reads: hgq, the 1-point rule's incremental hourglass
# forces (a 2x2 run held it unused, so its checkpoint restarts)
LEGACY_FIELDS = ("hgq",)


def write_checkpoint(path, st, ctx, driver_state):
    """Write the checkpoint of a run's state ``st`` (its context ``ctx``) (collective);
    ``driver_state`` is a JSON-able dict (schedules, frame count, segments: the same on every
    rank) plus, on rank 0, the driver's arrays under ``arrays``."""
    comm, s, lay = ctx.comm, st.store, ctx.layout
    rank0 = comm.rank == 0
    # What rank 0 alone knows: the state's text and the driver arrays' shapes
    meta = None
    if rank0:
        arrays = driver_state.get("arrays", {})
        state = {"t": st.t, "nstep": st.nstep, "dt": st.dt, "dt_prev": st.dt_prev}
        state.update({k: v for k, v in driver_state.items() if k != "arrays"})
        meta = (json.dumps(state), {k: (np.shape(a), np.asarray(a).dtype.str)
                                    for k, a in arrays.items()})
    state_text, shapes = comm.bcast(meta, root=0)
    # This rank's rows: the global bodies on rank 0 only, the owned grains everywhere
    bodies = np.arange(s.nb_own) if rank0 else np.arange(ctx.nglobal, s.nb_own)
    gids = s.gid[bodies]
    nidx, eidx = ranges(s.nstart[bodies], s.nn[bodies]), ranges(s.estart[bodies], s.ne[bodies])
    gn = ranges(lay.node_start[gids], s.nn[bodies])
    ge = ranges(lay.elem_start[gids], s.ne[bodies])
    extra = {"contact_force": st.fc} if ctx.has_contact else {}
    parts = {}
    for kind, loc, glob, n in ((BODY, bodies, gids, lay.nbody), (NODE, nidx, gn, lay.nnode),
                               (ELEM, eidx, ge, lay.nelem)):
        cols, table = _columns(s, ctx.fields, kind, loc, extra if kind == NODE else {})
        parts[kind] = (cols, to_blocks(comm, glob, table, n), n)
    hist = _history_blocks(comm, s, ctx.nglobal, lay.nbody - ctx.nglobal, lay.nbody)
    tmp = path + ".part"
    with h5py.File(tmp, "w", driver="mpio", comm=comm) as f:
        f.attrs["format"] = FORMAT
        f.attrs["pdfem_version"] = __version__
        f.attrs["scene"] = ctx.scene.to_toml_string()
        f.attrs["fields"] = json.dumps([fl.name for fl in ctx.fields])
        f.attrs["nranks"] = comm.size
        f.attrs["state"] = state_text
        # Bodies, nodes, elements: each rank its block of every field
        for kind, (cols, (lo, hi, blk), n) in parts.items():
            col = 0
            for name, shape, dtype in cols:
                width = int(np.prod(shape, dtype=np.int64))
                d = f.create_dataset(f"{GROUPS[kind]}/{name}", (n,) + shape, dtype)
                if hi > lo:
                    d[lo:hi] = blk[:, col:col + width].reshape((hi - lo,) + shape).astype(dtype)
                col += width
        _write_history(f, comm, lay.nbody, *hist)
        # The driver's series, from rank 0
        for name, (shape, dtype) in shapes.items():
            d = f.create_dataset(f"driver/{name}", shape, dtype)
            if rank0 and d.size:
                d[...] = driver_state["arrays"][name]
    comm.Barrier()
    if rank0:
        os.replace(tmp, path)
    comm.Barrier()


def _columns(s, fields, kind, loc, extra):
    """([(name, trailing shape, dtype)], (len(loc), k) float64 table) of the fields of one
    kind (and the extra node arrays) at the local rows ``loc``; integers are exact."""
    cols, parts = [], []
    for f in fields:
        if f.kind == kind:
            cols.append((f.name, f.shape, np.dtype(f.dtype)))
            parts.append(getattr(s, f.name)[loc])
    for name, arr in extra.items():
        cols.append((name, arr.shape[1:], arr.dtype))
        parts.append(arr[loc])
    widths = [int(np.prod(c[1], dtype=np.int64)) for c in cols]
    table = np.concatenate([p.reshape(loc.shape[0], w).astype(np.float64)
                            for p, w in zip(parts, widths, strict=True)], axis=1)
    return cols, table


def _history_blocks(comm, s, nglobal, ngrain, nbody):
    """This rank's block of the history rows by body: (lo, hi, rows (m, 6) = body, key,
    value, sorted). Each owned grain's rows go under it; rows between global bodies (and
    walls) only are rank 0's, under their first body."""
    key, val = s.hkey, s.hval
    owned = s.gid[nglobal:s.nb_own]
    a, b = key[:, 0], key[:, 2]
    only_global = (a >= ngrain) & ((b < 0) | (b >= ngrain))
    homes = [(a, np.isin(a, owned)), (b, np.isin(b, owned)),
             (a, only_global & (comm.rank == 0))]
    rows = np.concatenate([np.column_stack([h[m], key[m], val[m]]).astype(np.float64)
                           for h, m in homes]) if key.shape[0] else np.zeros((0, 6))
    # Each row to the rank whose block of bodies holds its body
    dest = block_owner(rows[:, 0], nbody, comm.size)
    got = alltoallv(comm, [rows[dest == r].ravel() for r in range(comm.size)])
    mine = np.concatenate([g.reshape(-1, 6) for g in got])
    lo, hi = block_bounds(nbody, comm.size, comm.rank)
    # Sorted by (body, key); a row found twice (a grain's contact with itself) kept once
    if mine.shape[0]:
        _, first = np.unique(mine[:, :5], axis=0, return_index=True)
        mine = mine[first]
    return lo, hi, mine


def _write_history(f, comm, nbody, lo, hi, rows):
    """The history datasets: each rank its block's rows, after the blocks before it."""
    count = rows.shape[0]
    before = comm.exscan(count) or 0
    total = comm.allreduce(count, op=MPI.SUM)
    per_body = np.bincount(rows[:, 0].astype(np.int64) - lo, minlength=hi - lo)
    start = f.create_dataset("history/start", (nbody + 1,), "i8")
    key = f.create_dataset("history/key", (total, 4), "i8")
    value = f.create_dataset("history/value", (total,), "f8")
    if hi > lo:
        start[lo:hi] = before + np.concatenate(([0], np.cumsum(per_body)[:-1]))
    if comm.rank == comm.size - 1:
        start[nbody] = total
    if count:
        key[before:before + count] = rows[:, 1:5].astype(np.int64)
        value[before:before + count] = rows[:, 5]


class Checkpoint:
    """A read checkpoint on one rank: the state dict, the global bodies and this rank's
    block of grains as one Batch (globals first, then grains, by gid), the driver arrays,
    and the contact forces of the batch's nodes (None without contact)."""

    def __init__(self, path, scene_text, state, batch, arrays, contact_force):
        self.path, self.scene_text = path, scene_text
        self.state, self.batch, self.arrays = state, batch, arrays
        self.contact_force = contact_force


def read_checkpoint(path, fields, comm=None, scene_check=None):
    """Read a checkpoint (collective on ``comm``, default this process alone); InputError
    naming the file, on every rank, when it cannot be used. ``scene_check(path, scene_text)``,
    when given, judges the checkpoint's scene before its fields are compared with ``fields``
    (a scene that differs is named by what differs, not by the fields that follow from it).

    Read by schema: attributes are JSON and TOML text, datasets numbers of the fields'
    shapes; a file that lacks an entry or whose rows do not add up is refused, never half
    used.
    """
    comm = comm if comm is not None else MPI.COMM_SELF
    out, msg = None, None
    try:
        out = _read(path, fields, comm, scene_check)
    except InputError as exc:
        msg = str(exc)
    # Every rank refuses when one does (each reads other rows)
    msgs = [m for m in comm.allgather(msg) if m]
    if msgs:
        raise InputError(msgs[0])
    return out


def _read(path, fields, comm, scene_check):
    """:func:`read_checkpoint` on one rank."""
    try:
        with h5py.File(path, "r", driver="mpio", comm=comm) as f:
            if f.attrs.get("format") != FORMAT:
                raise InputError(f"--restart: {path} is not a pdfem checkpoint of this version "
                                 f"(format {f.attrs.get('format')}; this version reads "
                                 f"{FORMAT})")
            if scene_check is not None:
                scene_check(path, str(f.attrs["scene"]))
            names = json.loads(f.attrs["fields"])
            want = [fl.name for fl in fields]
            if [n for n in names if n not in LEGACY_FIELDS] != want:
                why = ("1-point hourglass forces of an earlier version: run the scene anew"
                       if "hgq" in names and "hgref" in want else "different effects or model")
                raise InputError(f"--restart: {path} holds fields {names}; this scene needs "
                                 f"{want} ({why})")
            state = json.loads(f.attrs["state"])
            scene_text = str(f.attrs["scene"])
            batch, fc = _bodies(f, fields, comm)
            arrays = {k: _numbers(f["driver"][k]) for k in f["driver"]} if "driver" in f else {}
        tomllib.loads(scene_text)
    except OSError as exc:
        raise InputError(f"--restart: cannot read {path}: {_one_line(exc)}") from None
    except (KeyError, ValueError, TypeError, IndexError, OverflowError) as exc:
        # json and TOML decode errors are ValueErrors; a missing entry is a KeyError
        raise InputError(f"--restart: {path} is not a complete pdfem checkpoint "
                         f"({type(exc).__name__}: {_one_line(exc)})") from None
    bad = [k for k in STATE_KEYS if not isinstance(state, dict) or isinstance(
        state.get(k), bool) or not isinstance(state.get(k), (int, float))]
    bad += [k for k in ARRAY_KEYS if k not in arrays]
    if bad:
        raise InputError(f"--restart: {path} is not a complete pdfem checkpoint (no {bad[0]})")
    return Checkpoint(path, scene_text, state, batch, arrays, fc)


def _bodies(f, fields, comm):
    """(Batch of the global bodies and this rank's block of grains, their contact forces or
    None); ValueError when the datasets do not fit together."""
    nn = _numbers(f["bodies/nn"], ())
    nb = nn.shape[0]
    ne = _numbers(f["bodies/ne"], (nb,))
    isglobal = _numbers(f["bodies/isglobal"], (nb,))
    ngrain = int((isglobal == 0).sum())
    if (nn < 0).any() or (ne < 0).any() or (isglobal[:ngrain] != 0).any():
        raise ValueError("body counts are negative or the grains are not the first bodies")
    # The global bodies, then this rank's block of grains, by gid; their node and element
    # rows (contiguous: a body's rows follow the bodies before it)
    lo, hi = block_bounds(ngrain, comm.size, comm.rank)
    spans = {BODY: [(ngrain, nb), (lo, hi)]}
    for kind, per in ((NODE, nn), (ELEM, ne)):
        first = np.concatenate(([0], np.cumsum(per)))
        spans[kind] = [(int(first[a]), int(first[b])) for a, b in spans[BODY]]
    counts = {BODY: nb, NODE: spans[NODE][0][1], ELEM: spans[ELEM][0][1]}
    arrays = {}
    for fl in fields:
        if fl.kind in GROUPS:
            d = f[f"{GROUPS[fl.kind]}/{fl.name}"]
            _numbers(d, (counts[fl.kind],) + fl.shape, read=False)
            arrays[fl.name] = np.concatenate([d[a:b] for a, b in spans[fl.kind]]).astype(
                fl.dtype)
    if not np.array_equal(arrays["gid"], np.concatenate([np.arange(a, b)
                                                         for a, b in spans[BODY]])):
        raise ValueError("the gid of a body is not its row")
    arrays["hkey"], arrays["hval"] = _history(f, nb, spans[BODY])
    fc = None
    if "contact_force" in f["nodes"]:
        d = f["nodes/contact_force"]
        _numbers(d, (counts[NODE], 2), read=False)
        fc = np.concatenate([d[a:b] for a, b in spans[NODE]]).astype(np.float64)
    return Batch(fields, arrays), fc


def _history(f, nb, spans):
    """The history rows of the bodies in ``spans``, once each, sorted by key."""
    start = f["history/start"]
    _numbers(start, (nb + 1,), read=False)
    key, value = f["history/key"], f["history/value"]
    nh = key.shape[0] if key.ndim else -1
    _numbers(key, (nh, 4), read=False)
    _numbers(value, (nh,), read=False)
    keys, vals = [], []
    for a, b in spans:
        r0, r1 = int(start[a]), int(start[b])
        if not 0 <= r0 <= r1 <= nh:
            raise ValueError("history/start does not fit history/key")
        keys.append(key[r0:r1])
        vals.append(value[r0:r1])
    keys = np.concatenate(keys) if keys else np.zeros((0, 4), np.int64)
    vals = np.concatenate(vals) if vals else np.zeros(0)
    if keys.shape[0] == 0:
        return keys.astype(np.int64), vals.astype(np.float64)
    keys, first = np.unique(keys.astype(np.int64), axis=0, return_index=True)
    return keys, vals[first].astype(np.float64)


def _numbers(dset, shape=None, read=True):
    """A dataset's values (or, read=False, the dataset) when it holds numbers of the given
    shape (``()`` for any 1-D length); TypeError or ValueError otherwise."""
    if not isinstance(dset, h5py.Dataset) or dset.dtype.kind not in "biuf":
        raise TypeError(f"{dset.name} is not a numeric dataset")
    if shape == () and dset.ndim != 1 or shape not in (None, ()) and dset.shape != shape:
        raise ValueError(f"{dset.name} has shape {dset.shape}, expected {shape or '(n,)'}")
    return dset[...] if read else dset


def _one_line(exc):
    """An exception's message on one line."""
    return " ".join(str(exc).split())

