"""The 1-point rule with the points hourglass stiffness through the command line: the small
shot-912 piston at 1500 m/s on level-2 kite meshes, the packaged scene's crystal on its
Hugoniot: fewer than 1 % of the grains' elements with a folded corner, the balance closed, the
same bits on 1 and 2 ranks."""

import numpy as np

from pdfem.mesh.quality import corner_jacobians
from tests.helpers import same_bits_on_one_and_two_ranks
from tests.scenes import packaged, write_scene


def _piston(out):
    """The packaged small scene at 1500 m/s for 0.12 us, 1 point, points stiffness, level 2."""
    doc = packaged("shot912_small.toml")
    for b in doc["blocks"] + doc["bc"]:
        if "velocity" in b:
            b["velocity"] = [0.0, -1500.0]
    doc["time"]["end"] = 1.2e-7
    doc["element"] = {"rule": "1pt", "level": 2, "hourglass_stiffness": "points"}
    doc["output"] = {"path": out, "interval": 2.0e-8, "energy_interval": 1.0e-8}
    doc.pop("shock")
    doc.pop("gauges")
    return doc


def test_points_stiffness_run_same_bits_on_one_and_two_ranks(tmp_path):
    write_scene(tmp_path / "s.toml", _piston("r.h5"))
    a = same_bits_on_one_and_two_ranks("s.toml", tmp_path)
    assert np.abs(a["energy/balance_error"]).max() < 0.01
    grains = np.nonzero(a["mesh/body_kind"] == 0)[0]
    conn = a["mesh/conn"][np.isin(a["mesh/elem_body"], grains)]
    folded = [(corner_jacobians(x, conn).min(axis=1) <= 0.0).mean() for x in a["frames/x"]]
    assert max(folded) < 0.01
