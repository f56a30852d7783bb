"""Gauges: element sets of a block side, point location, values of a rigid drift."""

import numpy as np
import pytest
from mpi4py import MPI

from pdfem.errors import InputError
from pdfem.gauges import Gauges, block_elements
from pdfem.scene import parse_scene
from pdfem.solver import Simulation
from tests.scenes import drifting_grains


def test_block_sides():
    # Element (i, j) of a 3 x 2 block is i + 3 j
    assert block_elements(3, 2, "bottom").tolist() == [0, 1, 2]
    assert block_elements(3, 2, "top").tolist() == [3, 4, 5]
    assert block_elements(3, 2, "left").tolist() == [0, 3]
    assert block_elements(3, 2, "right").tolist() == [2, 5]
    assert block_elements(3, 2, "all").tolist() == list(range(6))


def _sim(tmp_path, gauges):
    """Four drifting grains with the gauges ``gauges`` (a list of dicts)."""
    doc = drifting_grains(n=4, end=1e-6, out=str(tmp_path / "r.h5"), extra={"gauges": gauges})
    return Simulation(parse_scene(doc, tmp_path), MPI.COMM_SELF)


def test_point_gauge_reads_the_grain_it_sits_in(tmp_path):
    # Grain 0 is centred at (0.006, 0.0015): a rigid drift, so the gauge reads its velocity
    sim = _sim(tmp_path, [{"name": "g", "point": [0.006, 0.0015]}])
    g = Gauges(sim.state, sim.ctx)
    assert g.sets[0][0] == 0
    vals = g.values(sim.state, sim.ctx)
    v0 = sim.scene.grains["velocity"][0]
    assert np.allclose(vals[0, :2], v0, rtol=1e-12, atol=1e-9)
    assert np.all(vals[0, 2:] == 0.0)
    for _ in range(20):
        sim.step()
    g.sample(sim.state, sim.ctx)
    t, hist = g.history()
    assert t.shape == (1,) and np.allclose(hist[0, 0, :2], v0, rtol=1e-9)


def test_point_outside_every_element_is_an_input_error(tmp_path):
    """The error names the scene file and the key."""
    gauge = {"gauges": [{"name": "g", "point": [0.0239, 0.0059]}]}
    doc = drifting_grains(n=4, end=1e-6, out=str(tmp_path / "r.h5"), extra=gauge)
    sim = Simulation(parse_scene(doc, tmp_path, name="gauged.toml"), MPI.COMM_SELF)
    with pytest.raises(InputError, match=r"^gauged.toml: gauges\[0\]\.point: no element "
                       "contains"):
        Gauges(sim.state, sim.ctx)


def test_block_gauge_reads_the_contact_force_on_its_nodes(tmp_path):
    """A plate moving down onto a grain: the gauge of its bottom row reads the contact force
    on those nodes (N/m), which is minus the force on the grain (the contact law's forces add
    up to zero); before the contact it reads zero."""
    doc = {
        "domain": {"box": [0.0, 0.0, 1.0e-3, 1.0e-3]},
        "time": {"end": 1.0e-6, "safety": 0.5},
        "contact": {"kn0": 1.0e14, "delta_max": 2.0e-5},
        "materials": {"grain": {"density": 1900.0, "bulk": 12.7e9, "shear": 4.4e9},
                      "steel": {"density": 7850.0, "bulk": 160.0e9, "shear": 79.0e9}},
        "grains": [{"center": [5.0e-4, 4.0e-4], "axes": [2.0e-4, 1.5e-4],
                    "material": "grain"}],
        "blocks": [{"name": "plate", "box": [0.0, 5.52e-4, 1.0e-3, 6.5e-4], "nx": 4,
                    "material": "steel", "velocity": [0.0, -20.0]}],
        "gauges": [{"name": "g", "body": "plate", "side": "bottom"}],
        "output": {"path": str(tmp_path / "r.h5"), "interval": 1.0e-6},
    }
    sim = Simulation(parse_scene(doc, tmp_path), MPI.COMM_SELF)
    g = Gauges(sim.state, sim.ctx)
    assert np.all(g.values(sim.state, sim.ctx)[0, 6:] == 0.0)
    while sim.t < sim.t_end:
        sim.step()
    vals = g.values(sim.state, sim.ctx)
    s = sim.store
    grain = [b for b in range(s.nb_own) if not s.isglobal[b]][0]
    on_grain = sim.fc[s.nstart[grain]:s.nstart[grain] + s.nn[grain]].sum(axis=0)
    assert vals[0, 7] > 0.0 and on_grain[1] < 0.0
    assert np.allclose(vals[0, 6:], -on_grain, rtol=1e-9, atol=1e-9 * abs(on_grain[1]))
