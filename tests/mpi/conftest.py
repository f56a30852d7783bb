"""Under MPI a test that fails on one rank only would leave the others waiting in a
collective: print the failure and abort every rank so that ``mpirun`` ends instead."""

import sys

import pytest


@pytest.hookimpl(hookwrapper=True)
def pytest_runtest_makereport(item, call):
    """Abort the whole MPI job when a test fails on a rank of a multi-rank run."""
    outcome = yield
    report = outcome.get_result()
    if report.failed and call.when == "call":
        from mpi4py import MPI

        comm = MPI.COMM_WORLD
        if comm.size > 1:
            sys.stderr.write(f"[rank {comm.rank}] {item.nodeid} failed:\n{report.longreprtext}\n")
            sys.stderr.flush()
            comm.Abort(1)
