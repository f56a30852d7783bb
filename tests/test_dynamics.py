"""Whole-solver checks against closed forms: P-wave arrival, energy of a free vibration."""

import numpy as np
import pytest
from mpi4py import MPI

from pdfem.kernels import params as P
from pdfem.scene import parse_scene
from pdfem.solver import Simulation
from tests.scenes import elastic, stretched_block

RHO, K, G = 1900.0, 12.7e9, 4.4e9
CP = np.sqrt((K + 4 * G / 3) / RHO)


@pytest.mark.parametrize("rule", ["1pt", "2x2"])
def test_p_wave_arrives_at_L_over_cp(tmp_path, rule):
    # A bar in uniaxial strain (rollers top and bottom), velocity step at the left end
    length, v0 = 0.02, 1.0
    doc = stretched_block(end=float(1.2 * length / CP), rule=rule, nx=400, ny=2, v=v0)
    doc["bc"] += [{"body": "bar", "nodes": side, "type": "roller"} for side in ("top", "bottom")]
    # Fixed left end, pulled right end: the tension front reaches the left end at L/c_p
    sim = Simulation(parse_scene(doc, str(tmp_path)), MPI.COMM_SELF)
    left = np.nonzero(sim.store.elem_loc % 400 == 0)[0]
    plateau = RHO * CP * v0
    arrival = None
    while sim.t < sim.t_end:
        sim.step()
        sxx = sim.store.sig[left, :, 0].mean()
        if arrival is None and sxx >= 0.5 * plateau:
            arrival = sim.t
    assert arrival is not None
    assert arrival == pytest.approx(length / CP, rel=0.02)


def test_free_vibration_conserves_energy(tmp_path):
    # One undamped grain, breathing and shearing from an initial velocity field
    doc = {
        "domain": {"box": [-0.002, -0.002, 0.002, 0.002]},
        "time": {"end": 1.0, "safety": 0.5, "max_steps": 10000},
        "element": {"rule": "2x2", "level": 2},
        "output": {"path": "vib.h5", "interval": 1.0, "energy_interval": 1.0},
        "materials": {"grain": elastic()},
        "grains": [{"center": [0.0, 0.0], "axes": [5.0e-4, 3.0e-4], "material": "grain"}],
    }

    def shake(sim, store):
        x = store.x
        store.v[:, 0] = 20.0 * x[:, 0] / 5e-4 + 10.0 * x[:, 1] / 3e-4
        store.v[:, 1] = -15.0 * x[:, 1] / 3e-4

    sim = Simulation(parse_scene(doc, str(tmp_path)), MPI.COMM_SELF, init_state=shake)
    from pdfem.energy import global_terms

    e0 = None
    worst = 0.0
    for n in range(10000):
        sim.step()
        if n % 500 == 0 or n == 9999:
            terms = global_terms(sim.state, sim.ctx)
            e = terms["kinetic"] + terms["strain"]
            e0 = e if e0 is None else e0
            worst = max(worst, abs(e - e0) / e0)
            assert terms["strain"] > 0
    assert worst < 0.005
    assert sim.mat_params[0, P.RHO] == RHO
