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
The file is written as ``<path>.part`` and renamed to ``<path>`` only when complete.
"""

import os

import h5py
import numpy as np
from mpi4py import MPI

from pdfem import __version__
from pdfem.io.gather import to_blocks
from pdfem.io.layout import FRAME_LAYOUT
from pdfem.io.xdmf import write_xdmf
from pdfem.store import ranges


def frame_fields(nip, fields):
    """The frame datasets of a run: the scene's output.fields, plus ``stress_cell`` (the
    element mean) when elements have several integration points."""
    out = list(fields)
    if "stress" in out and nip > 1:
        out.insert(out.index("stress") + 1, "stress_cell")
    return out


def field_table(sim):
    """{name: (node|elem, trailing shape, values(nidx, eidx))} of every frame field, laid out
    as :data:`pdfem.io.layout.FRAME_LAYOUT` says."""
    s = sim.store

    def emean(a, e):
        return a[e].mean(axis=1)

    values = {
        "x": lambda n, e: s.x[n],
        "v": lambda n, e: s.v[n],
        "temperature": lambda n, e: s.T[n],
        "contact_force": lambda n, e: sim.fc[n],
        "stress": lambda n, e: s.sig[e],
        "stress_cell": lambda n, e: emean(s.sig, e),
        "kappa": lambda n, e: s.mst[e, :, 0].mean(axis=1),
        "plastic_strain": lambda n, e: s.mst[e, :, 2:6].mean(axis=1),
        "element_temperature": lambda n, e: s.T[s.conn[e]].mean(axis=1),
    }
    return {name: (per, tuple(sim.nip if n is None else n for n in tail), values[name])
            for name, (per, tail) in FRAME_LAYOUT.items()}


class RunWriter:
    """Collective writer of frames and the energy series of one run."""

    def __init__(self, path, sim, nframes, fields=("x", "v", "stress"), resume=None):
        comm = sim.comm
        self.comm, self.path = comm, path
        self.fields = tuple(frame_fields(sim.nip, fields))
        self.tmp = path + ".part"
        self.nframes_max = nframes
        self.resumed = False
        if resume is not None and self._reopen(sim, resume):
            return
        self.f = h5py.File(self.tmp, "w", driver="mpio", comm=comm)
        layout = sim.layout
        self.nn_tot, self.ne_tot = layout.nnode, layout.nelem
        f = self.f
        self._attrs(sim)
        # Static mesh description (written by rank 0: it is known to every rank)
        mesh = f.create_group("mesh")
        dsets = {
            "node_body": mesh.create_dataset("node_body", (self.nn_tot,), "i8"),
            "conn": mesh.create_dataset("conn", (self.ne_tot, 4), "i8"),
            "elem_body": mesh.create_dataset("elem_body", (self.ne_tot,), "i8"),
            "elem_material": mesh.create_dataset("elem_material", (self.ne_tot,), "i4"),
            "body_kind": mesh.create_dataset("body_kind", (layout.nbody,), "i1"),
        }
        fr = f.create_group("frames")
        # Frame datasets hold at most nframes; they are cut to the frames written at close
        table = field_table(sim)
        shapes = {name: ((self.nn_tot,) if kind == "node" else (self.ne_tot,)) + shp
                  for name, (kind, shp, _) in table.items()}
        # Parallel HDF5 allocates chunked datasets at once: start small, grow by doubling
        cap = min(nframes, 8)
        self.time = fr.create_dataset("time", (cap,), "f8", maxshape=(None,))
        self.dsets = {}
        for name in self.fields:
            shp = shapes[name]
            self.dsets[name] = fr.create_dataset(name, (cap,) + shp, "f8",
                                                 maxshape=(None,) + shp,
                                                 chunks=(1,) + tuple(max(1, n) for n in shp))
        self.nframe = 0
        self._write_mesh(sim, dsets)

    def _attrs(self, sim):
        f = self.f
        f.attrs["scene"] = sim.scene.to_toml_string()
        f.attrs["effects"] = ",".join(sim.effect_names)
        f.attrs["pdfem_version"] = __version__
        f.attrs["nranks"] = self.comm.size

    def _reopen(self, sim, nframe):
        """Continue ``<path>.part`` after a restart: keep its first ``nframe`` frames.

        Returns False (the caller starts a new file) when the file is missing or unreadable,
        e.g. torn by a process killed in the middle of a write.
        """
        ok = os.path.exists(self.tmp)
        if ok:
            try:
                f = h5py.File(self.tmp, "r+", driver="mpio", comm=self.comm)
            except OSError:
                ok = False
        ok = self.comm.allreduce(int(ok), op=MPI.MIN) == 1
        if not ok:
            return False
        self.f = f
        self.nn_tot, self.ne_tot = sim.layout.nnode, sim.layout.nelem
        fr = f["frames"]
        self.time = fr["time"]
        self.dsets = {name: fr[name] for name in self.fields}
        self.nframe = int(nframe)
        self._attrs(sim)
        self.resumed = True
        return True

    def _rows(self, sim):
        """Global node and element indices of this rank's rows (globals on rank 0 only)."""
        s, lay = sim.store, sim.layout
        bodies = np.arange(s.nb_own)
        if self.comm.rank != 0:
            bodies = bodies[s.isglobal[: s.nb_own] == 0]
        gids = s.gid[bodies]
        nidx = ranges(s.nstart[bodies], s.nn[bodies])
        eidx = ranges(s.estart[bodies], s.ne[bodies])
        gn = ranges(lay.node_start[gids], s.nn[bodies])
        ge = ranges(lay.elem_start[gids], s.ne[bodies])
        return nidx, eidx, gn, ge

    def _write_mesh(self, sim, dsets):
        s, lay = sim.store, sim.layout
        nidx, eidx, gn, ge = self._rows(sim)
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

    def write_frame(self, sim):
        """Write the frame fields of every body at the current time (collective)."""
        nidx, eidx, gn, ge = self._rows(sim)
        k = self.nframe
        if k >= self.time.shape[0]:
            # Collective: every rank writes every frame, so all resize together
            cap = min(2 * self.time.shape[0], max(self.nframes_max, k + 1))
            self.time.resize((cap,))
            for d in self.dsets.values():
                d.resize((cap,) + d.shape[1:])
        # (global rows, local values) of each field, by name
        table = field_table(sim)
        for name in self.dsets:
            kind, _, values = table[name]
            idx, n = (gn, self.nn_tot) if kind == "node" else (ge, self.ne_tot)
            lo, hi, blk = to_blocks(self.comm, idx, values(nidx, eidx), n)
            d = self.dsets[name]
            if hi > lo:
                d[k, lo:hi] = blk.reshape((hi - lo,) + d.shape[2:])
        # Every rank writes the (same) time: a write by one rank alone can allocate a chunk
        # of a reopened file on that rank only, and the collective close then hangs
        self.time[k] = sim.t
        self.nframe += 1

    def suspend(self):
        """Flush and close without finishing: a restart continues this ``.part`` file."""
        self.f.close()
        self.comm.Barrier()

    def close(self, energy_rows, terms, ok=True, gauges=None):
        """Write the energy series and gauges (rank 0 holds them), close, rename into place."""
        comm = self.comm
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
        self.time.resize((self.nframe,))
        for d in self.dsets.values():
            d.resize((self.nframe,) + d.shape[1:])
        self.f.close()
        comm.Barrier()
        if comm.rank == 0:
            if ok:
                os.replace(self.tmp, self.path)
                write_xdmf(self.path)
            else:
                os.remove(self.tmp)
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
