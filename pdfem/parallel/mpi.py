"""MPI helpers: the communicators, abort on uncaught exceptions, reductions, broadcasts,
gathers and buffer exchanges.

Every collective of the solver outside this package (and io's parallel writer) goes through
these wrappers, so that mpi4py is imported here alone. Each is the single MPI call it names;
a one-rank fast path is taken only where it returns the identical value.
"""

import sys
from contextlib import contextmanager

import numpy as np
from mpi4py import MPI


def world():
    """The world communicator, with uncaught exceptions aborting every rank (never a hang)."""
    comm = MPI.COMM_WORLD
    # Wrapped once: a second call must not stack another abort on the first
    if comm.size > 1 and not getattr(sys.excepthook, "aborts_all", False):
        hook = sys.excepthook

        def abort_all(kind, value, tb):
            hook(kind, value, tb)
            sys.stderr.flush()
            comm.Abort(1)

        abort_all.aborts_all = True
        sys.excepthook = abort_all
    return comm


def self_comm():
    """A communicator of this process alone (a serial run inside an MPI job)."""
    return MPI.COMM_SELF


@contextmanager
def alone(comm, root=0):
    """A one-rank communicator holding rank ``root`` of comm (None on the other ranks), freed
    on leaving the block; collective over comm."""
    solo = comm.Split(0 if comm.rank == root else MPI.UNDEFINED, 0)
    try:
        yield solo if comm.rank == root else None
    finally:
        if comm.rank == root:
            solo.Free()


def barrier(comm):
    """Wait until every rank of comm reaches this point."""
    comm.Barrier()


def broadcast(comm, obj, root=0):
    """Rank root's (picklable) object, on every rank."""
    return comm.bcast(obj, root=root)


def gather_objects(comm, obj, root=0):
    """Every rank's (picklable) object, in rank order, on root (None elsewhere)."""
    return comm.gather(obj, root=root)


def allgather_objects(comm, obj):
    """Every rank's (picklable) object, in rank order, on every rank."""
    return comm.allgather(obj)


def global_min(comm, value):
    """The least of a float over every rank."""
    return comm.allreduce(float(value), op=MPI.MIN) if comm.size > 1 else float(value)


def global_any(comm, flag):
    """True when the flag is true on any rank."""
    return bool(comm.allreduce(int(bool(flag)), op=MPI.MAX)) if comm.size > 1 else bool(flag)


def global_max(comm, value):
    """The largest of a float over every rank."""
    return comm.allreduce(float(value), op=MPI.MAX) if comm.size > 1 else float(value)


def global_sum(comm, value):
    """The sum of an int over every rank (exact)."""
    return comm.allreduce(int(value), op=MPI.SUM) if comm.size > 1 else int(value)


def array_max(comm, a):
    """The elementwise largest of a float64 array (the same shape on every rank) over every
    rank; a new array."""
    a = np.ascontiguousarray(a, np.float64)
    out = np.empty_like(a)
    comm.Allreduce(a, out, op=MPI.MAX)
    return out


def array_sum(comm, a):
    """The elementwise sum of a float64 array (the same shape on every rank) over every rank,
    in place; returns a. Rounded: the same on any rank count only where one rank holds a
    non-zero value per entry."""
    comm.Allreduce(MPI.IN_PLACE, a, op=MPI.SUM)
    return a


def global_sum_exact(comm, k):
    """The elementwise sum of an int64 array over every rank: exact, so the same in any order
    and on any rank count (the caller keeps the total within int64); a new array."""
    k = np.ascontiguousarray(k, np.int64)
    out = np.empty_like(k)
    comm.Allreduce(k, out, op=MPI.SUM)
    return out


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
