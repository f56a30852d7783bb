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
    text = drifting_grains(n=4, end=1e-6, out=str(tmp_path / "r.h5"), extra=gauges)
    return Simulation(parse_scene(text, tmp_path), MPI.COMM_SELF)


def test_point_gauge_reads_the_grain_it_sits_in(tmp_path):
    # Grain 0 is centred at (0.006, 0.0015): a rigid drift, so the gauge reads its velocity
    sim = _sim(tmp_path, '[[gauges]]\nname = "g"\npoint = [0.006, 0.0015]\n')
    g = Gauges(sim)
    assert g.sets[0][0] == 0
    vals = g.values(sim)
    v0 = sim.scene.grains["velocity"][0]
    assert np.allclose(vals[0, :2], v0, rtol=1e-12, atol=1e-9)
    assert np.all(vals[0, 2:] == 0.0)
    for _ in range(20):
        sim.step()
    g.sample(sim)
    t, hist = g.history()
    assert t.shape == (1,) and np.allclose(hist[0, 0, :2], v0, rtol=1e-9)


def test_point_outside_every_element_is_an_input_error(tmp_path):
    sim_text = '[[gauges]]\nname = "g"\npoint = [0.0239, 0.0059]\n'
    with pytest.raises(InputError, match=r"gauges\[0\]\.point: no element contains"):
        Gauges(_sim(tmp_path, sim_text))
