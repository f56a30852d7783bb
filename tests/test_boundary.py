"""A driven body brought to rest and released (pdfem.boundary): the profile, the integrator's
velocities under it, the freed nodes, and the work its reaction does."""

import numpy as np
import pytest
from mpi4py import MPI

from pdfem.boundary import factor
from pdfem.energy import global_terms
from pdfem.scene import parse_scene
from pdfem.solver import Simulation

V, RELEASE, RAMP = 10.0, 2.0e-6, 1.0e-6


def test_factor_profile():
    """1 before the ramp, linear to 0 at the release, 0 after; no ramp: a step."""
    assert factor(0.0, RELEASE, RAMP) == 1.0
    assert factor(RELEASE - RAMP, RELEASE, RAMP) == 1.0
    assert factor(RELEASE - 0.25 * RAMP, RELEASE, RAMP) == pytest.approx(0.25)
    assert factor(RELEASE, RELEASE, RAMP) == 0.0 and factor(5.0, RELEASE, RAMP) == 0.0
    assert factor(RELEASE - 1e-12, RELEASE, 0.0) == 1.0


def _scene():
    """A steel block driven upwards on an elastic block fixed at its bottom (they do not
    touch: no contact); released at RELEASE after a ramp of RAMP."""
    return {
        "domain": {"box": [0.0, 0.0, 1.0e-3, 1.0e-3]},
        "time": {"end": 3.0e-6, "safety": 0.5},
        "materials": {"steel": {"density": 7850.0, "bulk": 160.0e9, "shear": 79.0e9}},
        "blocks": [{"name": "piston", "box": [0.0, 0.5e-3, 1.0e-3, 0.6e-3],
                    "material": "steel", "velocity": [0.0, V]}],
        "bc": [{"body": "piston", "type": "velocity", "velocity": [0.0, V],
                "release": RELEASE, "ramp_down": RAMP}],
        "output": {"path": "run.h5", "interval": 1.0e-6},
    }


def test_driven_body_is_brought_to_rest_and_freed(tmp_path):
    """The block moves at V, then at V times the profile at the end of each half step, then
    freely (it keeps the rest it was brought to); the conditions are off after the release;
    the work of the reaction pays for the kinetic energy it took away."""
    sim = Simulation(parse_scene(_scene(), str(tmp_path)), MPI.COMM_SELF)
    s = sim.store
    e0 = global_terms(sim.state, sim.ctx)
    seen_ramp = False
    while sim.t < sim.t_end:
        sim.step()
        # The velocity of the half step after t: the profile at the end of its interval
        t_end = sim.t + sim.dt
        vy = sim.store.v[: s.nn_own, 1]
        if t_end < RELEASE:
            assert np.all(vy == pytest.approx(V * factor(t_end, RELEASE, RAMP), abs=1e-9))
            seen_ramp |= 0.1 < factor(t_end, RELEASE, RAMP) < 0.9
    assert seen_ramp
    assert np.all(sim.store.bcf[: s.nn_own] == 0)
    assert np.abs(sim.store.v[: s.nn_own]).max() < 1e-6 * V
    # Kinetic energy went from 1/2 m V^2 to zero; the reaction did that much negative work
    e1 = global_terms(sim.state, sim.ctx)
    assert e0["kinetic"] > 0 and e1["kinetic"] < 1e-9 * e0["kinetic"]
    assert e1["bc_work"] == pytest.approx(-e0["kinetic"], rel=1e-6)
