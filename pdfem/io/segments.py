"""Frame segments: the run file's frames in files that a kill cannot tear once closed.

An HDF5 file open for writing is consistent only after its close: its metadata (the chunk
indexes, the dataset shapes, the free-space lists) lives in a cache that is flushed in
pieces, so a process killed at any moment between the open and the close can leave a file
that no longer opens, or opens with wrong shapes, and everything in it is lost (the mpio run
file of this project no longer opened after a kill). Closing the run file at each checkpoint
and reopening it to append would rely on a kill during a later append leaving the file as it
was at its last close, which HDF5 does not promise: it has no journal, the metadata cache
writes entries in place when it evicts them, and the mpio driver flushes metadata
collectively; one torn append would lose every frame before the checkpoint. A collective
flush between frames desynchronises the metadata of the parallel file in this HDF5 build.

So the frames go to segment files. ``<run>.h5.part`` (segment 0) holds the mesh and the
frames up to the first checkpoint; each checkpoint closes the segment being written and
records in its state every closed segment as ``[first frame, frame count]``; the frames
after it go to a new segment ``<run>.h5.part.<i>``, created at its first frame (a run that
checkpoints every step and writes few frames opens few files). A kill can only tear the
segment being written, which no checkpoint refers to; a restart checks the checkpoint's
segments, deletes the later ones and writes its frames into a new segment. At the end of
the run the segments are joined: segment 0 is copied (a plain file copy) to
``<run>.h5.part.all``, the frames of the later segments are copied into it in parallel,
the energy series and gauges are added and the file is renamed to ``<run>.h5``; a kill
during the join leaves the segments as they were. A run that never checkpointed finishes
segment 0 in place, as before: no copy.

A rollback of the guards can set the frame count below the first frame of the segment
being written, or of closed ones: the open segment then restarts at that frame, and where
segments overlap the later one holds the valid frames.
"""

import os
import re
import shutil

import h5py
import numpy as np

from pdfem.io.gather import block_bounds


def segment_path(tmp, i):
    """The file of segment ``i`` of the run file ``tmp`` (``<run>.h5.part``)."""
    return tmp if i == 0 else f"{tmp}.{i}"


def join_path(tmp):
    """The file the segments are joined into before it is renamed to the run file."""
    return tmp + ".all"


def later_files(tmp, n):
    """The segment files of ``tmp`` from segment ``n`` on, and a join left by a kill."""
    folder = os.path.dirname(tmp) or "."
    base = os.path.basename(tmp)
    pat = re.compile(re.escape(base) + r"\.(\d+)$")
    out = [os.path.join(folder, name) for name in os.listdir(folder)
           if (m := pat.match(name)) and int(m.group(1)) >= n]
    if os.path.exists(join_path(tmp)):
        out.append(join_path(tmp))
    if n == 0 and os.path.exists(tmp):
        out.append(tmp)
    return sorted(out)


def valid_segments(segments):
    """True when a checkpoint's ``segments`` entry is a list of [first, count] frame pairs."""
    return isinstance(segments, list) and all(
        isinstance(s, list) and len(s) == 2 and all(type(v) is int and v >= 0 for v in s)
        for s in segments)


def check_segments(tmp, segments, shapes, mesh_shapes):
    """None when every segment of the list opens and holds its frames in the layout's
    shapes; else the one-line reason, naming the file (serial: rank 0 reads)."""
    for i, (_, count) in enumerate(segments):
        path = segment_path(tmp, i)
        try:
            with h5py.File(path, "r") as f:
                fr = f["frames"]
                if fr["time"].shape != (count,):
                    return f"{path} holds {fr['time'].shape[0]} frames, the checkpoint {count}"
                for name, shp in shapes.items():
                    if fr[name].shape != (count,) + shp:
                        return f"{path}: frames/{name} has shape {fr[name].shape}"
                for name, shp in mesh_shapes.items() if i == 0 else ():
                    if f["mesh"][name].shape != shp:
                        return f"{path}: mesh/{name} has shape {f['mesh'][name].shape}"
        except (OSError, KeyError, TypeError, ValueError) as exc:
            what = "missing" if not os.path.exists(path) else "unreadable"
            return f"{path} is {what} ({type(exc).__name__})"
    return None


def source_of(segments, nframe):
    """For each frame below ``nframe``: (segment, row) of its valid copy, the latest segment
    that holds it (-1 where none does)."""
    seg = np.full(nframe, -1, np.int64)
    row = np.zeros(nframe, np.int64)
    for i, (first, count) in enumerate(segments):
        hi = min(first + count, nframe)
        if hi > first:
            seg[first:hi] = i
            row[first:hi] = np.arange(hi - first)
    return seg, row


def copy_frames(comm, dst, tmp, segments, nframe, names, extra=None):
    """Copy into the frames group ``dst`` (sized to ``nframe``) the frames whose valid copy
    is in a segment after the first (collective: each rank copies its block of rows); with
    ``extra``, also ``extra(comm, dst_file, src_file, frames)`` per segment."""
    seg, row = source_of(segments, nframe)
    for i in range(1, len(segments)):
        frames = np.nonzero(seg == i)[0]
        if not frames.size:
            continue
        with h5py.File(segment_path(tmp, i), "r", driver="mpio", comm=comm) as f:
            src = f["frames"]
            # Every rank writes the (same) times: see RunWriter.write_frame
            dst["time"][frames] = src["time"][row[frames]]
            for name in names:
                d, s = dst[name], src[name]
                lo, hi = block_bounds(d.shape[1], comm.size, comm.rank)
                for k, r in zip(frames, row[frames], strict=True):
                    if hi > lo:
                        d[k, lo:hi] = s[r, lo:hi]
            if extra is not None:
                extra(comm, dst.file, f, frames)


def start_join(tmp):
    """Copy segment 0 to the join file (rank 0 only); return the join file's path."""
    shutil.copyfile(tmp, join_path(tmp))
    return join_path(tmp)
