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
import tomllib

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


# The state entries every checkpoint holds (numbers), and the driver arrays
STATE_KEYS = ("t", "nstep", "dt", "dt_prev", "nframe", "frames_k", "samples_k", "gauges_k",
              "checkpoint_k")
ARRAY_KEYS = ("energy_rows", "energy_ref")


def read_checkpoint(path, fields):
    """Read a checkpoint (every rank); InputError naming the file when it cannot be used.

    Read by schema: attributes are JSON and TOML text, datasets plain float arrays; a file
    that lacks an entry or whose buffers do not add up is refused, never half used.
    """
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
            scene_text = str(f.attrs["scene"])
            data = np.asarray(_numbers(f["buffers"]), np.float64)
            sizes = np.asarray(_numbers(f["buffer_sizes"]), np.int64)
            arrays = {k: _numbers(f["driver"][k]) for k in f["driver"]} if "driver" in f else {}
        tomllib.loads(scene_text)
        batch = _bodies(fields, data, sizes)
    except OSError as exc:
        raise InputError(f"--restart: cannot read {path}: {exc}") from None
    except (KeyError, ValueError, TypeError, IndexError, OverflowError) as exc:
        # json and TOML decode errors are ValueErrors; a missing entry is a KeyError
        raise InputError(f"--restart: {path} is not a complete pdfem checkpoint "
                         f"({type(exc).__name__}: {_one_line(exc)})") from None
    bad = [k for k in STATE_KEYS if not isinstance(state, dict) or isinstance(
        state.get(k), bool) or not isinstance(state.get(k), (int, float))]
    bad += [k for k in ARRAY_KEYS if k not in arrays]
    if bad:
        raise InputError(f"--restart: {path} is not a complete pdfem checkpoint (no {bad[0]})")
    return Checkpoint(path, scene_text, state, batch, arrays)


def _numbers(dset):
    """A dataset's values when they are numbers (never objects or strings)."""
    if not isinstance(dset, h5py.Dataset) or dset.dtype.kind not in "biuf":
        raise TypeError(f"{dset.name} is not a numeric dataset")
    return dset[...]


def _bodies(fields, data, sizes):
    """The bodies of the gathered rank buffers as one Batch; ValueError if they do not add
    up to the stored data."""
    if data.ndim != 1 or sizes.ndim != 1 or (sizes < 0).any() or sizes.sum() != data.size:
        raise ValueError("buffer sizes do not add up to the stored buffers")
    parts, off = [], 0
    for n in sizes:
        part, used = Batch.from_buffer(fields, data[off:off + n])
        if used != n:
            raise ValueError(f"a rank buffer holds {n} values, its bodies {used}")
        parts.append(part)
        off += n
    return Batch.concat(fields, parts)


def _one_line(exc):
    """An exception's message on one line."""
    return " ".join(str(exc).split())
