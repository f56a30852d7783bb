"""Ghosts of grains grown wider than the cells: a rank sees a grain two cells away.

Run under ``mpirun -n 2 python -m pytest --with-mpi tests/mpi``.
"""

import pytest
from mpi4py import MPI

from pdfem.scene import parse_scene
from pdfem.solver import Simulation
from tests.mpi.collective import assert_all
from tests.scenes import collision


@pytest.mark.mpi(min_size=2)
def test_a_grain_two_cells_away_is_a_ghost(tmp_path):
    """Two grains stretched to touch with centroids in cells 0 and 2 of a strip partition
    (rank 0 owns cells 0-1, rank 1 cells 2-3): after the rebuild each rank that owns one
    holds the other as a ghost, and its contact candidates include the pair."""
    comm = MPI.COMM_WORLD
    doc = collision(v=0.0)
    doc["domain"]["partition"] = "strips"
    sim = Simulation(parse_scene(doc, str(tmp_path)), comm)
    s, g0 = sim.store, sim.nglobal
    for b in range(g0, s.nb_own):
        i = slice(s.nstart[b], s.nstart[b] + s.nn[b])
        c = s.x[i].mean(axis=0)
        cx = 0.95e-3 if c[0] < 2.0e-3 else 2.05e-3
        s.x[i, 0] = cx + (s.x[i, 0] - c[0]) * (0.545e-3 / 0.4e-3)
    store, sim.halo, sim.state.reach = sim.rebuild(sim.store)
    sim.state.new_store(store)
    contact = next(e for e in sim.effects if e.name == "contact")
    contact.after_rebuild(sim.state, sim.ctx)
    s = sim.store
    owns = s.nb_own - g0
    assert_all(comm, sim.reach == 2, f"reach {sim.reach}")
    assert_all(comm, owns <= 1 and comm.allreduce(owns) == 2, f"rank {comm.rank} owns {owns}")
    if owns:
        assert_all(comm, s.nbody - g0 == 2 and contact.gpairs.shape[0] == 1,
                   f"rank {comm.rank}: {s.nbody - g0} grains, {contact.gpairs.shape[0]} pairs")
    else:
        assert_all(comm, True)
