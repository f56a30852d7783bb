"""The state a step advances (pdfem.state): one owner, per-step arrays made in one place, and
a snapshot that puts a run back exactly."""

import numpy as np
import pytest
from mpi4py import MPI

from pdfem.guards import LastGood
from pdfem.scene import parse_scene
from pdfem.solver import Simulation
from pdfem.state import State
from tests import scenes


def _sim(tmp_path):
    return Simulation(parse_scene(scenes.collision(v=50.0, end=2e-6), str(tmp_path)),
                      MPI.COMM_SELF)


def test_per_step_arrays_follow_the_store(tmp_path):
    sim = _sim(tmp_path)
    st = sim.state
    nn, nb = st.store.v.shape[0], st.store.nbody
    assert st.f.shape == st.fc.shape == st.du.shape == (nn, 2)
    assert st.kin.shape == (nb,)
    # Without contact the contact forces are the (0, 2) "none" array
    assert State(st.store, contact=False).fc.shape == (0, 2)
    # A new store (a rebuild): the arrays are made again, zeroed
    st.f[:] = 1.0
    st.new_store(st.store)
    assert not st.f.any() and not st.du.any()


def test_the_stepper_shows_the_state_read_only(tmp_path):
    sim = _sim(tmp_path)
    sim.step()
    assert sim.t == sim.state.t and sim.nstep == sim.state.nstep == 1
    assert sim.store is sim.state.store and sim.fc is sim.state.fc
    for name in ("t", "dt", "nstep", "store", "f", "fc", "du", "kin"):
        with pytest.raises(AttributeError):
            setattr(sim, name, None)


def test_rollback_restores_the_snapshot_exactly(tmp_path):
    """Twenty steps, a snapshot, twenty more; back to the snapshot, the same twenty again:
    the same bits, and the restored state is the snapshot's."""
    sim = _sim(tmp_path)
    for _ in range(20):
        sim.step()
    last = LastGood(sim.state, sim.owner, {})
    t0, n0 = sim.t, sim.nstep
    for _ in range(20):
        sim.step()
    x1, v1, t1 = sim.store.x.copy(), sim.store.v.copy(), sim.t
    sim.restore(last)
    assert (sim.t, sim.nstep) == (t0, n0)
    for _ in range(20):
        sim.step()
    assert sim.t == t1
    assert np.array_equal(sim.store.x, x1) and np.array_equal(sim.store.v, v1)
