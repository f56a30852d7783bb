"""Contact across ranks: shear history travels with a migrating grain; forces match serial.

Run under ``mpirun -n 2 python -m pytest --with-mpi tests/mpi``.
"""

import numpy as np
import pytest
from mpi4py import MPI

from pdfem.scene import parse_scene
from pdfem.solver import Simulation
from tests.mpi.collective import assert_all
from tests.scenes import settling_bed


def _history(sim):
    """{key: shear history} of the contacts that involve a grain this rank owns."""
    s = sim.store
    owned = set(int(g) for g in s.gid[: s.nb_own])
    return {tuple(int(v) for v in k): float(h) for k, h in zip(s.hkey, s.hval, strict=True)
            if k[0] in owned or k[2] in owned}


@pytest.mark.mpi(min_size=2)
def test_history_survives_migration_and_matches_serial(tmp_path):
    comm = MPI.COMM_WORLD
    # A bed that slides sideways (tilted gravity) so grains cross the strip boundary
    doc = settling_bed(n=60, cols=10, g=-1.0e6, partition="strips")
    doc["gravity"]["g"] = [4.0e5, -1.0e6]
    par = Simulation(parse_scene(doc, str(tmp_path)), comm)
    ser = Simulation(parse_scene(doc, str(tmp_path)), MPI.COMM_SELF)
    owner_of = {}
    carried = 0
    # Step until a grain has changed rank holding a non-zero history (about 8100 steps)
    for _ in range(12000):
        if comm.allreduce(carried) > 0:
            break
        par.step()
        ser.step()
        s = par.store
        # Grains that changed rank while holding a non-zero shear history
        now = {int(g): comm.rank for g in s.gid[: s.nb_own][s.isglobal[: s.nb_own] == 0]}
        allnow = {}
        for d in comm.allgather(now):
            allnow.update(d)
        hist = _history(par)
        moved = [g for g, r in allnow.items() if g in owner_of and owner_of[g] != r]
        for g in moved:
            if allnow[g] == comm.rank:
                carried += sum(1 for k, h in hist.items() if (k[0] == g or k[2] == g) and h != 0)
        owner_of = allnow
        # Every history row this rank holds equals the serial run's, bit for bit
        ref = {tuple(int(v) for v in k): float(h) for k, h in zip(ser.store.hkey,
                                                                  ser.store.hval, strict=True)}
        wrong = [k for k, h in hist.items() if ref.get(k) != h]
        assert_all(comm, not wrong, f"rank {comm.rank} step {par.nstep}: history {wrong[:3]}")
    assert_all(comm, comm.allreduce(carried) > 0, "no history migrated")
    # Forces and positions equal the serial run's too
    same = True
    for b in range(par.store.nb_own):
        gid = par.store.gid[b]
        rb = int(np.nonzero(ser.store.gid == gid)[0][0])
        i = slice(par.store.nstart[b], par.store.nstart[b] + par.store.nn[b])
        j = slice(ser.store.nstart[rb], ser.store.nstart[rb] + ser.store.nn[rb])
        same &= np.array_equal(par.store.x[i], ser.store.x[j])
        same &= np.array_equal(par.f[i], ser.f[j])
    assert_all(comm, same, f"rank {comm.rank}: state differs from the serial run")
