"""The grain's potential through the command line: the small shot-912 piston at 2000 m/s on
level-3 kite meshes (1 point, points stiffness), where grains used to pass into each other
once contacts reached only their boundary elements: no grain node inside another grain's
interior elements, the balance closed, the same bits on 1 and 2 ranks."""

import numpy as np

from pdfem.tools.analysis.interpenetration import nodes_inside_interiors
from tests.helpers import same_bits_on_one_and_two_ranks
from tests.scenes import packaged, write_scene


def _piston(out, end):
    """The packaged small scene at 2000 m/s to ``end``, 1 point, points stiffness, level 3."""
    doc = packaged("shot912_small.toml")
    for b in doc["blocks"] + doc["bc"]:
        if "velocity" in b:
            b["velocity"] = [0.0, -2000.0]
    doc["time"]["end"] = end
    doc["element"] = {"rule": "1pt", "level": 3, "hourglass_stiffness": "points"}
    doc["output"] = {"path": out, "interval": end / 4, "energy_interval": end / 20}
    doc.pop("shock")
    doc.pop("gauges")
    return doc


def test_grains_stay_out_of_each_others_insides_same_bits_on_one_and_two_ranks(tmp_path):
    write_scene(tmp_path / "s.toml", _piston("r.h5", 2.5e-7))
    a = same_bits_on_one_and_two_ranks("s.toml", tmp_path)
    assert np.abs(a["energy/balance_error"]).max() < 0.01
    grains = np.nonzero(a["mesh/body_kind"] == 0)[0]
    keep = np.isin(a["mesh/elem_body"], grains)
    conn, elem_body = a["mesh/conn"][keep], a["mesh/elem_body"][keep]
    inside = [nodes_inside_interiors(x, conn, elem_body, a["mesh/node_body"]).sum()
              for x in a["frames/x"]]
    assert len(inside) == 5 and max(inside) == 0
