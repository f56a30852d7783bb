"""The run file: one HDF5 file written by all ranks through h5py's mpio driver.

Layout (everything by global id, so 1-rank and N-rank files compare equal):
    /mesh/node_body (NN,), /mesh/conn (NE,4) global node ids, /mesh/elem_body (NE,),
    /mesh/elem_material (NE,), /mesh/body_kind (NB,) 0 grain 1 block
    /frames/time (F,), /frames/x (F,NN,2), /frames/v (F,NN,2), /frames/stress (F,NE,nip,4),
    /frames/temperature (F,NN) (only with [heat])
    /energy/time (E,) and one (E,) dataset per term, plus /energy/balance_error
    /gauges/time (G,), /gauges/NAME/velocity (G,2), /gauges/NAME/stress (G,4),
    /gauges/NAME/force (G,2) (contact force on the gauge elements' nodes, N/m),
    /gauges/NAME/elements (the gauge's element ids; attribute body) (with [[gauges]])
    attributes: scene (resolved TOML), effects, pdfem version
The file is written as ``<path>.part`` and renamed to ``<path>`` only when complete; after
a checkpoint the frames continue in segment files joined at the end (:mod:`pdfem.io.segments`).
"""

import os
from functools import partial

import h5py
import numpy as np

from pdfem import __version__
from pdfem.errors import InputError
from pdfem.io.contacts import contact_rows, copy_contacts, drop_after, write_contacts
from pdfem.io.gather import to_blocks
from pdfem.io.layout import frame_layout
from pdfem.io.segments import (
    check_segments,
    copy_frames,
    join_path,
    later_files,
    segment_path,
    start_join,
)
from pdfem.io.xdmf import write_xdmf
from pdfem.store import ranges


def frame_fields(nip, fields):
    """The frame datasets of a run: the scene's output.fields, plus ``stress_cell`` (the
    element mean) when elements have several integration points; ``contacts`` is not one
    (:mod:`pdfem.io.contacts`)."""
    out = [name for name in fields if name != "contacts"]
    if "stress" in out and nip > 1:
        out.insert(out.index("stress") + 1, "stress_cell")
    return out


def field_table(st, ctx):
    """{name: (node|elem, trailing shape, values(nidx, eidx))} of the run's frame fields: the
    core ones and those of its effects (Effect.frame_fields, Effect.frame_values), laid out
    as :func:`pdfem.io.layout.frame_layout` says of them."""
    s = st.store
    values = {
        "x": lambda n, e: s.x[n],
        "v": lambda n, e: s.v[n],
        "stress": lambda n, e: s.sig[e],
        "stress_cell": lambda n, e: s.sig[e].mean(axis=1),
    }
    for eff in ctx.effects:
        for name in eff.frame_fields:
            values[name] = partial(eff.frame_values, st, ctx, name)
    layout = frame_layout([type(eff) for eff in ctx.effects])
    out = {}
    for name, get in values.items():
        per, tail = layout[name]
        out[name] = (per, tuple(ctx.nip if n is None else n for n in tail), get)
    return out


class RunWriter:
    """Collective writer of frames and the energy series of one run, the frames in segment
    files (:mod:`pdfem.io.segments`) closed at each checkpoint."""

    def __init__(self, path, st, ctx, nframes, fields=("x", "v", "stress"), resume=None):
        comm = ctx.comm
        self.comm, self.path = comm, path
        self.fields = tuple(frame_fields(ctx.nip, fields))
        self.contacts = "contacts" in fields
        self.tmp = path + ".part"
        self.nframes_max = nframes
        self.nn_tot, self.ne_tot = ctx.layout.nnode, ctx.layout.nelem
        table = field_table(st, ctx)
        self.shapes = {name: ((self.nn_tot,) if kind == "node" else (self.ne_tot,)) + shp
                       for name, (kind, shp, _) in table.items() if name in self.fields}
        # Closed segments as [first frame, count]; the open one's index and first frame
        self.segments, self.f = [], None
        self.seg_first, self.nframe = 0, 0
        self.resumed = False
        if resume is not None and self._resume(st, ctx, *resume):
            return
        self._open_segment(0)
        self._attrs(st, ctx)
        layout = ctx.layout
        # Static mesh description (written by rank 0: it is known to every rank)
        mesh = self.f.create_group("mesh")
        dsets = {name: mesh.create_dataset(name, shp, dt)
                 for name, (shp, dt) in self._mesh_shapes(layout).items()}
        self._write_mesh(st, ctx, dsets)

    def _mesh_shapes(self, layout):
        """{name: (shape, dtype)} of the /mesh datasets."""
        return {"node_body": ((self.nn_tot,), "i8"), "conn": ((self.ne_tot, 4), "i8"),
                "elem_body": ((self.ne_tot,), "i8"), "elem_material": ((self.ne_tot,), "i4"),
                "body_kind": ((layout.nbody,), "i1")}

    def _open_segment(self, i):
        """Create segment ``i`` with empty frame datasets; its first frame is the next one."""
        self.f = h5py.File(segment_path(self.tmp, i), "w", driver="mpio", comm=self.comm)
        fr = self.f.create_group("frames")
        # Parallel HDF5 allocates chunked datasets at once: start small, grow by doubling
        cap = max(1, min(self.nframes_max - self.nframe, 8))
        self.time = fr.create_dataset("time", (cap,), "f8", maxshape=(None,))
        self.dsets = {}
        for name in self.fields:
            shp = self.shapes[name]
            self.dsets[name] = fr.create_dataset(name, (cap,) + shp, "f8",
                                                 maxshape=(None,) + shp,
                                                 chunks=(1,) + tuple(max(1, n) for n in shp))
        self.seg_first = self.nframe

    def _attrs(self, st, ctx):
        f = self.f
        f.attrs["scene"] = ctx.scene.to_toml_string()
        f.attrs["effects"] = ",".join(ctx.effect_names)
        f.attrs["pdfem_version"] = __version__
        f.attrs["nranks"] = self.comm.size

    def _resume(self, st, ctx, nframe, segments):
        """Continue the segments of a checkpoint: check them, delete the later ones; the
        next frame opens a new segment. Returns False (the caller starts a new run file)
        when the checkpoint lists no segments or segment 0 is gone (a restart into another
        run file, or after the run completed); InputError naming a damaged segment."""
        comm, where = self.comm, None
        if comm.rank == 0:
            where = "fresh"
            if segments and os.path.exists(self.tmp):
                where = check_segments(self.tmp, segments, self.shapes,
                                       {k: v[0] for k, v in self._mesh_shapes(
                                           ctx.layout).items()})
            # Segments after the checkpoint's (torn or not) are not part of the run
            stale = {None: len(segments), "fresh": 1}.get(where)
            for name in later_files(self.tmp, stale) if stale is not None else ():
                os.remove(name)
        where = comm.bcast(where, root=0)
        if where == "fresh":
            return False
        if where is not None:
            raise InputError(f"--restart: frame segment {where}; restart into another run "
                             f"file (-o) to start its frames at the checkpoint")
        self.segments = [list(s) for s in segments]
        self.nframe = int(nframe)
        self.resumed = True
        return True

    def _rows(self, st, ctx):
        """Global node and element indices of this rank's rows (globals on rank 0 only)."""
        s, lay = st.store, ctx.layout
        bodies = np.arange(s.nb_own)
        if self.comm.rank != 0:
            bodies = bodies[s.isglobal[: s.nb_own] == 0]
        gids = s.gid[bodies]
        nidx = ranges(s.nstart[bodies], s.nn[bodies])
        eidx = ranges(s.estart[bodies], s.ne[bodies])
        gn = ranges(lay.node_start[gids], s.nn[bodies])
        ge = ranges(lay.elem_start[gids], s.ne[bodies])
        return nidx, eidx, gn, ge

    def _write_mesh(self, st, ctx, dsets):
        s, lay = st.store, ctx.layout
        nidx, eidx, gn, ge = self._rows(st, ctx)
        gconn = s.lconn[eidx] + lay.node_start[s.elem_gid[eidx]][:, None]
        for name, idx, rows, n in (("node_body", gn, s.gid[s.node_body[nidx]], self.nn_tot),
                                   ("conn", ge, gconn, self.ne_tot),
                                   ("elem_body", ge, s.elem_gid[eidx], self.ne_tot),
                                   ("elem_material", ge, s.emat[eidx], self.ne_tot)):
            lo, hi, blk = to_blocks(self.comm, idx, rows, n)
            if hi > lo:
                dsets[name][lo:hi] = blk.astype(dsets[name].dtype).reshape((hi - lo,)
                                                                            + dsets[name].shape[1:])
        if self.comm.rank == 0:
            dsets["body_kind"][:] = lay.kind

    def write_frame(self, st, ctx):
        """Write the frame fields of every body at the current time (collective)."""
        if self.f is None:
            self._open_segment(len(self.segments))
        # A rollback to before the open segment's first frame: it restarts there
        self.seg_first = min(self.seg_first, self.nframe)
        nidx, eidx, gn, ge = self._rows(st, ctx)
        k = self.nframe - self.seg_first
        if k >= self.time.shape[0]:
            # Collective: every rank writes every frame, so all resize together
            cap = min(2 * self.time.shape[0], max(self.nframes_max - self.seg_first, k + 1))
            self.time.resize((cap,))
            for d in self.dsets.values():
                d.resize((cap,) + d.shape[1:])
        # (global rows, local values) of each field, by name
        table = field_table(st, ctx)
        for name in self.dsets:
            kind, _, values = table[name]
            idx, n = (gn, self.nn_tot) if kind == "node" else (ge, self.ne_tot)
            lo, hi, blk = to_blocks(self.comm, idx, values(nidx, eidx), n)
            d = self.dsets[name]
            if hi > lo:
                d[k, lo:hi] = blk.reshape((hi - lo,) + d.shape[2:])
        if self.contacts:
            write_contacts(self.comm, self.f, self.nframe, contact_rows(st, ctx))
        # Every rank writes the (same) time: a write by one rank alone can allocate a chunk
        # of a reopened file on that rank only, and the collective close then hangs
        self.time[k] = st.t
        self.nframe += 1

    def _cut(self):
        """Frame datasets of the open segment cut to the frames it holds (collective)."""
        first = min(self.seg_first, self.nframe)
        count = self.nframe - first
        self.time.resize((count,))
        for d in self.dsets.values():
            d.resize((count,) + d.shape[1:])
        if self.contacts:
            drop_after(self.f, self.nframe)
        return [first, count]

    def close_segment(self):
        """Close the open segment and add it to :attr:`segments` (collective); the next
        frame opens a new one. A checkpoint written after this refers to it."""
        if self.f is None:
            return
        seg = self._cut()
        self.f.close()
        self.f = None
        self.segments.append(seg)
        self.comm.Barrier()

    def suspend(self):
        """Close without finishing: a restart continues from the checkpoint's segments."""
        if self.f is not None:
            self.f.close()
            self.f = None
        self.comm.Barrier()

    def close(self, energy_rows, terms, ok=True, gauges=None):
        """Write the energy series and gauges (rank 0 holds them), close, rename into place.
        After a checkpoint the segments are joined first (:mod:`pdfem.io.segments`)."""
        comm = self.comm
        src = None
        if self.segments:
            # Every segment closed; segment 0 copied, the later ones' frames copied in
            self.close_segment()
            src = join_path(self.tmp)
            if comm.rank == 0:
                start_join(self.tmp)
            comm.Barrier()
            self.f = h5py.File(src, "r+", driver="mpio", comm=comm)
            fr = self.f["frames"]
            self.time, self.dsets = fr["time"], {name: fr[name] for name in self.fields}
            self.seg_first = 0
            self._cut()
            copy_frames(comm, fr, self.tmp, self.segments, self.nframe, self.fields,
                        copy_contacts if self.contacts else None)
            self.f.attrs["nranks"] = comm.size
        else:
            self._cut()
        if gauges is not None and len(gauges):
            self._write_gauges(gauges)
        n = comm.bcast(len(energy_rows) if comm.rank == 0 else None, root=0)
        g = self.f.create_group("energy")
        cols = ("time",) + tuple(terms) + ("total", "balance_error")
        ds = {c: g.create_dataset(c, (n,), "f8") for c in cols}
        if comm.rank == 0 and n:
            arr = np.array(energy_rows)
            for i, c in enumerate(cols):
                ds[c][:] = arr[:, i]
        self.f.close()
        comm.Barrier()
        if comm.rank == 0:
            if ok:
                os.replace(src or self.tmp, self.path)
                write_xdmf(self.path)
            # The segments are no longer needed once the run file is in place
            for name in later_files(self.tmp, 0):
                os.remove(name)
        comm.Barrier()

    def _write_gauges(self, gauges):
        """/gauges/time and per gauge velocity (G, 2), stress (G, 4) and contact force (G, 2)
        (collective)."""
        comm = self.comm
        hist = gauges.history() if comm.rank == 0 else None
        n = comm.bcast(hist[0].shape[0] if hist else None, root=0)
        g = self.f.create_group("gauges")
        t = g.create_dataset("time", (n,), "f8")
        ds = []
        for name in gauges.names:
            sub = g.create_group(name)
            ds.append((sub.create_dataset("velocity", (n, 2), "f8"),
                       sub.create_dataset("stress", (n, 4), "f8"),
                       sub.create_dataset("force", (n, 2), "f8")))
        # The element ids as a dataset: an attribute holds at most 64 KiB (8192 elements)
        elem_ds = []
        for (gid, elems), name in zip(gauges.sets, gauges.names, strict=True):
            g[name].attrs["body"] = gid
            elem_ds.append((g[name].create_dataset("elements", (len(elems),), "i8"), elems))
        if comm.rank == 0:
            for d, elems in elem_ds:
                if len(elems):
                    d[:] = elems
        if comm.rank == 0 and n:
            t[:] = hist[0]
            for i, (dv, dsig, dfor) in enumerate(ds):
                dv[:] = hist[1][:, i, :2]
                dsig[:] = hist[1][:, i, 2:6]
                dfor[:] = hist[1][:, i, 6:]
