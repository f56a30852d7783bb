"""The drift check's fixed-point energy sums: the same bits on 2 ranks as on 1, and within
n q / 2 of the exact sums (n bodies, q the term's quantum).

Run under ``mpirun -n 2 python -m pytest --with-mpi tests/mpi``.
"""

import math

import numpy as np
import pytest
from mpi4py import MPI

from pdfem.energy import QBITS, body_terms, fixed_point_terms, global_terms
from pdfem.scene import parse_scene
from pdfem.solver import Simulation
from tests.mpi.collective import assert_all
from tests.scenes import settling_bed


def _quanta(sim):
    """Each term's quantum, from the largest magnitude over every body (as the check does)."""
    rows = body_terms(sim.state, sim.ctx)
    top = np.abs(rows).max(axis=0) if rows.shape[0] else np.zeros(len(sim.terms))
    gtop = np.empty_like(top)
    sim.comm.Allreduce(top, gtop, op=MPI.MAX)
    n = sim.layout.nbody
    return [math.ldexp(1.0, math.frexp(v)[1] - QBITS + (n - 1).bit_length()) if v > 0 else 0.0
            for v in gtop]


@pytest.mark.mpi(min_size=2)
def test_fixed_point_terms_match_one_rank_bit_for_bit(tmp_path):
    comm = MPI.COMM_WORLD
    doc = settling_bed(n=60, cols=10, partition="strips")
    par = Simulation(parse_scene(doc, str(tmp_path)), comm)
    ser = Simulation(parse_scene(doc, str(tmp_path)), MPI.COMM_SELF)
    ref = comm.bcast(global_terms(par.state, par.ctx), root=0)
    n = par.layout.nbody
    for _ in range(4):
        for _ in range(300):
            par.step()
            ser.step()
        a, b = fixed_point_terms(par.state, par.ctx), fixed_point_terms(ser.state, ser.ctx)
        assert_all(comm, a == b, f"rank {comm.rank} step {par.nstep}: {a} != {b}")
        exact = comm.bcast(global_terms(par.state, par.ctx), root=0)
        q = _quanta(par)
        off = [t for i, t in enumerate(par.terms)
               if not abs(a[t] - exact[t]) <= 0.5 * n * q[i] + 1e-15 * abs(exact[t])]
        assert_all(comm, not off, f"step {par.nstep}: {off} beyond n q / 2 of the exact sums")
    # Motion happened: the sums are not all zero
    assert_all(comm, a["kinetic"] > 0 and a["potential"] != ref["potential"])
