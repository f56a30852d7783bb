"""Contact candidates of grains grown larger than the cell size: the cell reach.

The cell grid is sized for the grains as they start; grains flattened in a compacted bed
grow wider, and two of them can then touch with centroids two cells apart. The rebuild's
reach (pdfem.parallel.exchange.cell_reach) widens the candidate search and the ghost
neighbourhood so that no such pair is missed.
"""

import numpy as np
from mpi4py import MPI

from pdfem.kernels.neighbours import grain_pairs
from pdfem.scene import parse_scene
from pdfem.solver import Simulation
from tests.scenes import collision


def _stretched_pair(tmp_path):
    """Two round grains (radius 0.4 mm, cells 1 mm) stretched in x to half-widths of
    0.545 mm, centroids at 0.95 and 2.05 mm (cells 0 and 2), 10 µm apart (skin 50 µm)."""
    sim = Simulation(parse_scene(collision(v=0.0), str(tmp_path)), MPI.COMM_SELF)
    s, g0 = sim.store, sim.nglobal
    for b, cx in zip(range(g0, s.nb_own), (0.95e-3, 2.05e-3), strict=True):
        i = slice(s.nstart[b], s.nstart[b] + s.nn[b])
        c = s.x[i].mean(axis=0)
        s.x[i, 0] = cx + (s.x[i, 0] - c[0]) * (0.545e-3 / 0.4e-3)
    return sim


def test_grains_wider_than_the_cells_stay_candidates(tmp_path):
    sim = _stretched_pair(tmp_path)
    assert sim.reach == 1
    store, sim.halo, sim.state.reach = sim.rebuild(sim.store)
    sim.state.new_store(store)
    contact = next(e for e in sim.effects if e.name == "contact")
    contact.after_rebuild(sim.state, sim.ctx)
    g0 = sim.nglobal
    # The centroids are two cells apart: the 3x3 block would not see the pair
    assert sim.reach == 2
    assert [sorted(p) for p in contact.gpairs.tolist()] == [[g0, g0 + 1]]
    # The search of reach 1 misses it (what the fixed 3x3 block did)
    s = sim.store
    cent = np.array([s.x[s.nstart[b]:s.nstart[b] + s.nn[b]].mean(axis=0)
                     for b in range(g0, s.nb_own)])
    cells = sim.grid.cell_of(cent)
    assert (cells % sim.grid.nx).tolist() == [0, 2]
    boxes = np.array([[*s.x[s.nstart[b]:s.nstart[b] + s.nn[b]].min(axis=0),
                       *s.x[s.nstart[b]:s.nstart[b] + s.nn[b]].max(axis=0)]
                      for b in range(g0, s.nb_own)])
    owned = np.ones(2, np.int8)
    g = sim.grid
    assert grain_pairs(cells, owned, boxes, g.nx, g.ny, sim.skin, 1, 0.0).shape[0] == 0
    assert grain_pairs(cells, owned, boxes, g.nx, g.ny, sim.skin, 2, 0.0).shape[0] == 1
