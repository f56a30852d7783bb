"""Checkpoints: everything a run needs to continue, in one HDF5 file written atomically.

Every rank packs its owned bodies (with their contact history) into one float64 buffer
(:meth:`pdfem.store.Batch.to_buffer`; global bodies from rank 0 only); rank 0 gathers the
buffers and writes, serially, ``<path>.part``, then renames it over ``<path>``. A process
killed at any moment therefore leaves either the previous checkpoint or the new one, never
a torn file. The file also holds the step count, time, current and previous time step, the
output schedules, the energy series so far and its reference, and the gauge histories.
There is no random state to save: runs draw no random numbers after set-up.

Restart (:func:`read_checkpoint`) works on any number of ranks: every rank reads the
bodies, keeps the global ones and the grains whose centroid cell it owns, and the usual
rebuild makes the ghosts; the result is bit-identical to the run that never stopped.
"""

import json
import os

import h5py
import numpy as np

from pdfem import __version__
from pdfem.errors import InputError
from pdfem.store import Batch

FORMAT = 1


def write_checkpoint(path, sim, driver_state):
    """Write the checkpoint of ``sim`` (collective); ``driver_state`` is a JSON-able dict
    known on rank 0 (schedules, frame count, run file) plus arrays under ``arrays``."""
    comm, s = sim.comm, sim.store
    first = 0 if comm.rank == 0 else sim.nglobal
    buf = s.take(np.arange(first, s.nb_own)).to_buffer()
    bufs = comm.gather(buf, root=0)
    if comm.rank == 0:
        tmp = path + ".part"
        with h5py.File(tmp, "w") as f:
            f.attrs["format"] = FORMAT
            f.attrs["pdfem_version"] = __version__
            f.attrs["scene"] = sim.scene.to_toml_string()
            f.attrs["fields"] = json.dumps([fl.name for fl in sim.fields])
            f.attrs["nranks"] = comm.size
            state = {"t": sim.t, "nstep": sim.nstep, "dt": sim.dt, "dt_prev": sim.dt_prev}
            state.update({k: v for k, v in driver_state.items() if k != "arrays"})
            f.attrs["state"] = json.dumps(state)
            f.create_dataset("buffers", data=np.concatenate(bufs))
            f.create_dataset("buffer_sizes", data=np.array([b.size for b in bufs], np.int64))
            for name, arr in driver_state.get("arrays", {}).items():
                f.create_dataset(f"driver/{name}", data=arr)
        os.replace(tmp, path)
    comm.Barrier()


class Checkpoint:
    """A read checkpoint: the state dict, the bodies as one Batch, the driver arrays."""

    def __init__(self, path, scene_text, state, batch, arrays):
        self.path, self.scene_text = path, scene_text
        self.state, self.batch, self.arrays = state, batch, arrays


def read_checkpoint(path, fields):
    """Read a checkpoint (every rank); InputError naming the file when it cannot be used."""
    try:
        with h5py.File(path, "r") as f:
            if f.attrs.get("format") != FORMAT:
                raise InputError(f"--restart: {path} is not a pdfem checkpoint (format "
                                 f"{f.attrs.get('format')})")
            names = json.loads(f.attrs["fields"])
            if names != [fl.name for fl in fields]:
                raise InputError(f"--restart: {path} holds fields {names}; this scene needs "
                                 f"{[fl.name for fl in fields]} (different effects or model)")
            state = json.loads(f.attrs["state"])
            scene_text = f.attrs["scene"]
            data, sizes = f["buffers"][...], f["buffer_sizes"][...]
            arrays = {k: f["driver"][k][...] for k in f["driver"]} if "driver" in f else {}
    except OSError as exc:
        raise InputError(f"--restart: cannot read {path}: {exc}") from None
    parts, off = [], 0
    for n in sizes:
        parts.append(Batch.from_buffer(fields, data[off:off + n])[0])
        off += n
    return Checkpoint(path, scene_text, state, Batch.concat(fields, parts), arrays)
