"""The report's drive (pdfem/scenes/shot912_free.toml): the default scene with the hammer
free, and what a free hammer must do (give the bed exactly the momentum it loses)."""

import numpy as np
import pytest
from mpi4py import MPI

from pdfem.scene import parse_scene
from pdfem.solver import Simulation
from tests.scenes import packaged


def _free(doc):
    """A packaged piston scene with the hammer's velocity condition taken away."""
    doc["bc"] = [b for b in doc["bc"] if not (b["body"] == "hammer" and b["type"] == "velocity")]
    return doc


def test_the_free_scene_is_the_default_one_without_the_piston():
    """Everything but the drive, the steel's Hugoniot, the end and the run file is the default
    scene's, so that the two runs differ by the drive alone."""
    free, piston = packaged("shot912_free.toml"), packaged("shot912.toml")
    assert not any(b["body"] == "hammer" for b in free["bc"])
    assert free["materials"]["steel"].pop("eos") == "us_up"
    assert free["materials"]["steel"].pop("eos_s") == 1.33
    assert free["time"].pop("end") == 1.0e-5
    assert free["output"].pop("path") == "shot912_free.h5"
    piston["time"].pop("end")
    piston["output"].pop("path")
    assert free == _free(piston)
    hammer = next(b for b in free["blocks"] if b["name"] == "hammer")
    assert hammer["velocity"] == [0.0, -288.0]
    parse_scene(packaged("shot912_free.toml"), ".")


def _momentum_y(sim):
    s = sim.store
    n = s.nn_own
    return float(np.sum(s.m[:n] * s.v[:n, 1]))


def _hammer_velocity(sim):
    s = sim.store
    b = sim.blocks.index("hammer")
    i = slice(s.nstart[b], s.nstart[b] + s.nn[b])
    return float(np.sum(s.m[i] * s.v[i, 1]) / s.m[i].sum())


def test_a_free_hammer_gives_the_bed_what_it_loses(tmp_path):
    """The small bed hit by the free hammer for 1 us, before the wave reaches the bottom: the
    y-momentum of hammer and bed stays what the hammer had (to round-off), and the hammer
    slows as it hands it over."""
    doc = _free(packaged("shot912_small.toml"))
    doc["time"]["end"] = 1.0e-6
    doc["shock"]["plots"] = "none"
    sim = Simulation(parse_scene(doc, str(tmp_path)), MPI.COMM_SELF)
    p0 = _momentum_y(sim)
    v0 = _hammer_velocity(sim)
    assert v0 == pytest.approx(-288.0, rel=1e-14)
    worst = 0.0
    while sim.t < sim.t_end:
        sim.step()
        worst = max(worst, abs(_momentum_y(sim) - p0))
    assert worst <= 1e-10 * abs(p0)
    # The hammer slowed by about the impulse of the piston's stress over its mass per area:
    # rho0 Us up t / (rho_steel h) = 1235 * 860 * 288 * 1e-6 / (7850 * 1.5e-3) = 26 m/s
    assert 10.0 < 288.0 + _hammer_velocity(sim) < 50.0
