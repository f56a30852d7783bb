"""Assertions that every rank evaluates together, so one failing rank never hangs the others."""

from mpi4py import MPI


def assert_all(comm, cond, msg=""):
    """Assert cond on every rank: all ranks fail together if any rank's cond is false."""
    ok = comm.allreduce(bool(cond), op=MPI.LAND)
    detail = [m for m in comm.allgather("" if cond else str(msg)) if m]
    assert ok, "; ".join(detail)
