"""Which collectives a step makes: counted through a communicator that records every
collective call and the function that made it.

Run under ``mpirun -n 2 python -m pytest --with-mpi tests/mpi``.
"""

import os
import sys
from collections import Counter

import pytest
from mpi4py import MPI

from pdfem.scene import parse_scene
from pdfem.solver import Simulation
from tests.mpi.collective import assert_all
from tests.scenes import settling_bed

COLLECTIVES = {"allreduce", "Allreduce", "allgather", "Allgather", "Allgatherv", "alltoall",
               "Alltoall", "Alltoallv", "bcast", "Bcast", "gather", "Gather", "Gatherv",
               "Barrier", "barrier", "reduce", "Reduce", "scatter", "Scatter", "scan", "exscan"}


class CountingComm:
    """A communicator that counts its collective calls by (caller, method): the caller is
    the first function outside the MPI helpers of pdfem/parallel/mpi.py."""

    def __init__(self, comm):
        self._comm = comm
        self.calls = Counter()

    def __getattr__(self, name):
        attr = getattr(self._comm, name)
        if name not in COLLECTIVES:
            return attr

        def counted(*args, **kwargs):
            # Named by the first caller outside the MPI helpers (pdfem/parallel/mpi.py)
            frame = sys._getframe(1)
            while frame.f_code.co_filename.endswith(os.path.join("parallel", "mpi.py")):
                frame = frame.f_back
            self.calls[(frame.f_code.co_name, name)] += 1
            return attr(*args, **kwargs)

        return counted


@pytest.mark.mpi(min_size=2)
def test_a_step_makes_one_reduction(tmp_path):
    """A settling bed with heat conduction, no blocks: a step that does not rebuild makes one
    collective, the time step's reduction, which also carries the rebuild flag and the
    conduction limit; a step that rebuilds adds the migration's exchanges."""
    heat = {"heat": {"initial": 300.0}, "conduction": {}}
    doc = settling_bed(n=60, cols=10, partition="strips", extra=heat)
    doc["materials"]["grain"].update(specific_heat=1000.0, conductivity=1.0e6)
    comm = CountingComm(MPI.COMM_WORLD)
    sim = Simulation(parse_scene(doc, str(tmp_path)), comm)
    plain = rebuilds = 0
    for _ in range(1500):
        comm.calls.clear()
        store = sim.store
        sim.step()
        calls = dict(comm.calls)
        if sim.store is not store:
            rebuilds += 1
            assert_all(MPI.COMM_WORLD, calls.get(("next_dt", "Allreduce")) == 1,
                       f"step {sim.nstep}: {calls}")
            continue
        plain += 1
        assert_all(MPI.COMM_WORLD, calls == {("next_dt", "Allreduce"): 1},
                   f"step {sim.nstep}: {calls}")
    # Conduction was sub-cycled (its limit came with the time step), and steps rebuilt
    assert_all(MPI.COMM_WORLD, plain > 1000 and rebuilds > 0 and sim.heat.nsub > 1,
               f"{plain} plain steps, {rebuilds} rebuilds, {sim.heat.nsub} sub-steps")
