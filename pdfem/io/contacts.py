"""Per-contact output: every active contact of a frame's step, one group per frame.

With ``"contacts"`` in ``output.fields`` the run file holds ``/contacts/<frame>`` (the frame's
index, six digits) for every frame, each a group of datasets with one row per active contact
of the step that ended at the frame's time, in contact-key order (so 1- and N-rank files
compare equal):

    key (C, 4) int64     body A, its element, body B (-1 - wall index for a domain wall),
                         its element (0 for a wall); body and element ids as in /mesh
                         (elements numbered within their body)
    element (C, 2) int64 the two elements' global ids in /mesh/conn (-1 for a wall)
    point (C, 2)         the contact point, the overlap's centroid [m]
    normal (C, 2)        unit normal from A into B
    overlap (C,)         mean normal overlap, area / length [m]
    width (C,)           width of the overlap along the tangent [m]
    force (C, 2)         normal and shear force on A along the normal and the tangent
                         (-ny, nx) [N/m]; the normal force is <= 0 (tension positive)
    slip_rate (C,)       frictional slip of the step over the step [m/s]
    dissipation (C,)     frictional dissipation of the step over the step [W/m]
    heat (C,)            heat conducted across from B into A over the step [W/m] (0 without
                         [contact_conductance]); the friction heat is fraction x dissipation

Rates are of the one step that ended at the frame (not averages over the interval). The rows
are gathered on rank 0, sorted and written by it into contiguous datasets that every rank
creates (a contiguous dataset is allocated at creation, so one rank may write it alone).
A contact is counted by the rank that counts its energy (the owner of side A's body;
rank 0 for a block's).
"""

import numpy as np

from pdfem.kernels.contact import (
    C_ACTIVE,
    R_CX,
    R_CY,
    R_DELTA,
    R_DISS,
    R_FN,
    R_FS,
    R_NX,
    R_NY,
    R_WIDTH,
)
from pdfem.parallel.mpi import gather_rows

# Columns of a row: the datasets in file order, each with its trailing shape and dtype
COLUMNS = (("key", (4,), "i8"), ("element", (2,), "i8"), ("point", (2,), "f8"),
           ("normal", (2,), "f8"), ("overlap", (), "f8"), ("width", (), "f8"),
           ("force", (2,), "f8"), ("slip_rate", (), "f8"), ("dissipation", (), "f8"),
           ("heat", (), "f8"))
NCOL = sum(int(np.prod(shp, dtype=np.int64)) for _, shp, _ in COLUMNS)
GROUP = "contacts"


def frame_name(k):
    """The group name of frame ``k``."""
    return f"{k:06d}"


def contact_rows(st, ctx):
    """(n, NCOL) float rows of the active contacts this rank counts at the last evaluation
    (none before the first); ids are exact in float64 (below 2^53)."""
    last = ctx.contact.last if ctx.contact is not None else None
    if last is None:
        return np.zeros((0, NCOL))
    s = st.store
    active, keys, res, elems = last["active"], last["keys"], last["res"], last["elems"]
    body = s.elem_body[elems[:, 0]]
    own = body < s.nb_own
    if ctx.comm.rank != 0:
        own &= s.isglobal[body] == 0
    sel = np.nonzero((active == C_ACTIVE) & own)[0]
    dt = last["dt"]
    rate = 1.0 / dt if dt > 0.0 else 0.0
    k, r = keys[sel], res[sel]
    lay_start = ctx.layout.elem_start
    ga = lay_start[k[:, 0]] + k[:, 1]
    wall = k[:, 2] < 0
    gb = np.where(wall, -1, lay_start[np.where(wall, 0, k[:, 2])] + k[:, 3])
    fs = np.abs(r[:, R_FS])
    slip = np.divide(r[:, R_DISS], fs, out=np.zeros(sel.shape[0]), where=fs > 0.0)
    q = last.get("q")
    cond = (q[sel, 0] - q[sel, 2]) if q is not None else np.zeros(sel.shape[0])
    return np.column_stack([k, ga, gb, r[:, R_CX], r[:, R_CY], r[:, R_NX], r[:, R_NY],
                            r[:, R_DELTA], r[:, R_WIDTH], r[:, R_FN], r[:, R_FS], slip * rate,
                            r[:, R_DISS] * rate, cond * rate]).astype(np.float64)


def split_rows(rows):
    """{dataset: values} of :func:`contact_rows` rows, columns as in the file."""
    out, c = {}, 0
    for name, shp, dt in COLUMNS:
        w = int(np.prod(shp, dtype=np.int64))
        out[name] = rows[:, c:c + w].reshape((rows.shape[0],) + shp).astype(dt)
        c += w
    return out


def _create(f, k, n):
    """Create frame ``k``'s group with room for n contacts (collective), replacing an earlier
    copy (a rollback rewrites frames)."""
    g = f.require_group(GROUP)
    name = frame_name(k)
    if name in g:
        del g[name]
    sub = g.create_group(name)
    return {c: sub.create_dataset(c, (n,) + shp, dt) for c, shp, dt in COLUMNS}


def write_contacts(comm, f, k, rows):
    """Write this rank's contact ``rows`` (:func:`contact_rows`) as frame ``k`` of the open
    file ``f`` (collective): gathered on rank 0, sorted by key, written by rank 0."""
    got = gather_rows(comm, rows) if comm.size > 1 else rows
    n = comm.bcast(got.shape[0] if comm.rank == 0 else None, root=0)
    dsets = _create(f, k, n)
    if comm.rank == 0 and n:
        keys = got[:, :4]
        order = np.lexsort((keys[:, 3], keys[:, 2], keys[:, 1], keys[:, 0]))
        for name, values in split_rows(got[order]).items():
            dsets[name][...] = values


def drop_after(f, nframe):
    """Delete the contact groups of frames from ``nframe`` on (collective)."""
    g = f.get(GROUP)
    if g is None:
        return
    for name in [n for n in g if int(n) >= nframe]:
        del g[name]


def copy_contacts(comm, dst, src, frames):
    """Copy the contact groups of ``frames`` from the open file ``src`` into ``dst``
    (collective; rank 0 reads and writes)."""
    for k in frames:
        g = src[GROUP][frame_name(k)]
        n = g["key"].shape[0]
        dsets = _create(dst, k, n)
        if comm.rank == 0 and n:
            for name, d in dsets.items():
                d[...] = g[name][...]


def read_contacts(f, k):
    """{dataset: array} of frame ``k``'s contacts in the open run file ``f``; KeyError when
    the run has no per-contact output."""
    g = f[GROUP][frame_name(k)]
    return {name: g[name][...] for name, _, _ in COLUMNS}
