"""Ghost state equals owner state; a migrating grain keeps its id and its whole state.

Run under ``mpirun -n 2 python -m pytest --with-mpi tests/mpi``.
"""

import numpy as np
import pytest
from mpi4py import MPI

from pdfem.scene import parse_scene
from pdfem.solver import Simulation
from pdfem.store import ranges
from tests.mpi.collective import assert_all
from tests.scenes import drifting_grains


def _owned_records(sim):
    """{gid: (x, v)} of the grains this rank owns."""
    s = sim.store
    out = {}
    for b in range(s.nb_own):
        if s.isglobal[b]:
            continue
        idx = ranges(s.nstart[b : b + 1], s.nn[b : b + 1])
        out[int(s.gid[b])] = (s.x[idx].copy(), s.v[idx].copy())
    return out


@pytest.mark.mpi(min_size=2)
def test_ghosts_equal_owners(tmp_path):
    comm = MPI.COMM_WORLD
    scene = parse_scene(drifting_grains(n=16), str(tmp_path))
    sim = Simulation(scene, comm)
    checked = 0
    for _ in range(40):
        sim.step()
        sim.neighbourhood()  # refresh ghosts with the current owner state
        owners = {}
        for rec in comm.allgather(_owned_records(sim)):
            owners.update(rec)
        s = sim.store
        same = True
        for b in range(s.nb_own, s.nbody):
            idx = ranges(s.nstart[b : b + 1], s.nn[b : b + 1])
            x, v = owners[int(s.gid[b])]
            same &= np.array_equal(s.x[idx], x) and np.array_equal(s.v[idx], v)
            checked += 1
        assert_all(comm, same, f"rank {comm.rank}: a ghost differs from its owner")
    assert_all(comm, comm.allreduce(checked) > 0)


@pytest.mark.mpi(min_size=2)
def test_migration_keeps_id_and_state(tmp_path):
    comm = MPI.COMM_WORLD
    doc = drifting_grains(n=6, speed=2000.0, end=8e-6, frac=0.3)
    scene = parse_scene(doc, str(tmp_path))
    par = Simulation(scene, comm)
    ser = Simulation(parse_scene(doc, str(tmp_path)), MPI.COMM_SELF)
    owners_seen = {}
    for _ in range(300):
        par.step()
        ser.step()
        s = par.store
        for b in range(s.nb_own):
            owners_seen.setdefault(int(s.gid[b]), set()).add(comm.rank)
    # Grains crossed ranks, and each is now owned by exactly one rank
    seen = {}
    for d in comm.allgather(owners_seen):
        for g, r in d.items():
            seen.setdefault(g, set()).update(r)
    assert_all(comm, sum(len(r) > 1 for r in seen.values()) >= 2, "too few grains migrated")
    allmine = comm.allgather(sorted(_owned_records(par)))
    assert_all(comm, sorted(g for lst in allmine for g in lst) == list(range(6)))
    # Whole state of each owned grain equals the serial run's, bit for bit
    sref = ser.store
    bad = []
    for b in range(par.store.nb_own):
        gid = par.store.gid[b]
        rb = int(np.nonzero(sref.gid == gid)[0][0])
        pa, se = par.store.take([b]), sref.take([rb])
        bad += [f.name for f in par.store.fields
                if f.kind != "pair" and not np.array_equal(pa.a[f.name], se.a[f.name])]
    assert_all(comm, not bad, f"rank {comm.rank}: fields differ from serial: {bad}")
