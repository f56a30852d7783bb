"""MPI helpers: the world communicator, abort on uncaught exceptions, buffer exchanges."""

import sys

import numpy as np
from mpi4py import MPI


def world():
    """The world communicator, with uncaught exceptions aborting every rank (never a hang)."""
    comm = MPI.COMM_WORLD
    if comm.size > 1:
        hook = sys.excepthook

        def abort_all(kind, value, tb):
            hook(kind, value, tb)
            sys.stderr.flush()
            comm.Abort(1)

        sys.excepthook = abort_all
    return comm


def global_min(comm, value):
    """The least of a float over every rank."""
    return comm.allreduce(float(value), op=MPI.MIN) if comm.size > 1 else float(value)


def broadcast(comm, obj, root=0):
    """A picklable object from ``root`` on every rank."""
    return comm.bcast(obj, root=root) if comm.size > 1 else obj


def global_any(comm, flag):
    """True when the flag is true on any rank."""
    return bool(comm.allreduce(int(bool(flag)), op=MPI.MAX)) if comm.size > 1 else bool(flag)


def alltoallv(comm, bufs):
    """Send bufs[r] (float64 arrays) to rank r; return the list of buffers received."""
    size = comm.size
    scount = np.array([b.size for b in bufs], np.int64)
    rcount = np.empty(size, np.int64)
    comm.Alltoall(scount, rcount)
    sdisp = np.concatenate(([0], np.cumsum(scount)[:-1]))
    rdisp = np.concatenate(([0], np.cumsum(rcount)[:-1]))
    sbuf = np.concatenate(bufs) if bufs else np.zeros(0)
    rbuf = np.empty(int(rcount.sum()), np.float64)
    comm.Alltoallv([sbuf, (scount, sdisp), MPI.DOUBLE], [rbuf, (rcount, rdisp), MPI.DOUBLE])
    return [rbuf[rdisp[r] : rdisp[r] + rcount[r]] for r in range(size)]


def allgather_rows(comm, rows):
    """Concatenate a 2-D float64 array's rows from every rank, in rank order, on every rank."""
    rows = np.ascontiguousarray(rows, np.float64)
    ncol = rows.shape[1]
    counts = np.array(comm.allgather(rows.size), np.int64)
    out = np.empty(int(counts.sum()), np.float64)
    disp = np.concatenate(([0], np.cumsum(counts)[:-1]))
    comm.Allgatherv(rows.ravel(), [out, (counts, disp), MPI.DOUBLE])
    return out.reshape(-1, ncol)


def gather_rows(comm, rows, root=0):
    """Rows of a 2-D float64 array from every rank, concatenated in rank order on root."""
    rows = np.ascontiguousarray(rows, np.float64)
    ncol = rows.shape[1]
    counts = np.array(comm.allgather(rows.size), np.int64)
    out = np.empty(int(counts.sum()), np.float64) if comm.rank == root else None
    disp = np.concatenate(([0], np.cumsum(counts)[:-1]))
    recv = [out, (counts, disp), MPI.DOUBLE] if comm.rank == root else None
    comm.Gatherv(rows.ravel(), recv, root=root)
    return out.reshape(-1, ncol) if comm.rank == root else None
