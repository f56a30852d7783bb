"""Periodic sides across ranks: grains that drift out through the right side come back
through the left, meet grains across the seam as ghosts of the rank on the other side, and
every owned node's position and force equal the serial run's, bit for bit.

Run under ``mpirun -n 2 python -m pytest --with-mpi tests/mpi``.
"""

import numpy as np
import pytest
from mpi4py import MPI

from pdfem.scene import parse_scene
from pdfem.solver import Simulation
from tests.mpi.collective import assert_all
from tests.scenes import drifting_grains


def _seam_scene():
    """Eight grains on a 4 x 2 lattice 4 mm wide, drifting right at 400 m/s and more (with
    random sideways speeds), in contact: within 1500 steps (4.4 us) four have gone out
    through the right side, and pairs have touched across the seam."""
    doc = drifting_grains(n=8, box=(0.0, 0.0, 0.004, 0.002), speed=400.0, end=1.0, seed=5,
                          extra={"contact": {"kn0": 1.0e13, "delta_max": 1.0e-4,
                                             "friction": 0.3}})
    doc["domain"]["periodic"] = "x"
    return doc


@pytest.mark.mpi(min_size=2)
def test_grains_cross_the_seam_and_match_serial(tmp_path):
    comm = MPI.COMM_WORLD
    doc = _seam_scene()
    par = Simulation(parse_scene(doc, str(tmp_path)), comm)
    ser = Simulation(parse_scene(doc, str(tmp_path)), MPI.COMM_SELF)
    across = 0
    for _ in range(1500):
        par.step()
        ser.step()
        # Contacts met across the seam (a shift in the candidates) on this rank
        eff = next(e for e in par.effects if e.name == "contact")
        act = eff.last["active"] != 0
        cand = eff.detect.cand
        across += int(act.any() and np.any(cand[:, 2] != 0))
    s, r = par.store, ser.store
    # Every owned grain's nodes and forces equal the serial run's
    same = True
    for b in range(s.nb_own):
        rb = int(np.nonzero(r.gid == s.gid[b])[0][0])
        i = slice(s.nstart[b], s.nstart[b] + s.nn[b])
        j = slice(r.nstart[rb], r.nstart[rb] + r.nn[rb])
        same &= np.array_equal(s.x[i], r.x[j]) and np.array_equal(par.f[i], ser.f[j])
    assert_all(comm, same, f"rank {comm.rank}: state differs from the serial run")
    # Grains have gone out through the right side and are owned by the rank of their image
    x1 = par.grid.box[2]
    out = [int(s.gid[b]) for b in range(s.nb_own)
           if s.x[s.nstart[b]:s.nstart[b] + s.nn[b], 0].mean() > x1]
    assert_all(comm, comm.allreduce(len(out)) >= 2, "fewer than two grains crossed the seam")
    assert_all(comm, comm.allreduce(across) > 0, "no contact across the seam")
    owned = comm.allgather(sorted(int(g) for g in s.gid[: s.nb_own]))
    assert_all(comm, all(len(o) > 0 for o in owned), f"a rank owns no grain: {owned}")
