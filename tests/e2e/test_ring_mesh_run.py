"""The ring grain mesh through the command line: a packaged bed re-meshed onto rings, a
hammer at 1500 m/s that folds kite elements within 100 ns and no ring element in 200 ns; with
the crystal's equation of state the same bits on 1 and 2 ranks; a prepare scene that asks
for rings is refused with one line."""

import numpy as np

from pdfem.mesh.quality import corner_jacobians
from tests.helpers import datasets, pdfem, same_bits_on_one_and_two_ranks
from tests.scenes import packaged, small_prepare, write_scene


def _fast(out, mesh, eos=False, end=1.0e-7):
    """The small shot-912 piston at 1500 m/s to ``end`` on level-1 meshes, frames every 10 ns;
    eos: the grains' crystal on its Us-up Hugoniot (s = 2.29)."""
    doc = packaged("shot912_small.toml")
    v = 1500.0
    for b in doc["blocks"] + doc["bc"]:
        if "velocity" in b:
            b["velocity"] = [0.0, -v]
    doc["time"]["end"] = end
    doc["element"] = {"rule": "2x2", "level": 1, "mesh": mesh}
    doc["output"] = {"path": out, "interval": 1.0e-8, "energy_interval": 1.0e-8}
    if eos:
        doc["materials"]["hmx"].update(eos="us_up", eos_s=2.29)
    doc.pop("shock")
    doc.pop("gauges")
    return doc


def _folded(a):
    """Grain elements with a corner Jacobian <= 0, per frame."""
    grains = np.nonzero(a["mesh/body_kind"] == 0)[0]
    conn = a["mesh/conn"][np.isin(a["mesh/elem_body"], grains)]
    return np.array([(corner_jacobians(x, conn).min(axis=1) <= 0.0).sum()
                     for x in a["frames/x"]])


def test_ring_mesh_folds_later_than_kites(tmp_path):
    for mesh in ("ring", "kite"):
        write_scene(tmp_path / f"{mesh}.toml", _fast(f"{mesh}.h5", mesh, end=2.0e-7))
        p = pdfem(["run", f"{mesh}.toml", "--quiet"], tmp_path)
        assert p.returncode == 0, p.stderr
    ring, kite = datasets(tmp_path / "ring.h5"), datasets(tmp_path / "kite.h5")
    # 29 grains of 18 quads each (the kite mesh's 6)
    grains = np.nonzero(ring["mesh/body_kind"] == 0)[0]
    assert grains.shape[0] == 29
    assert np.all(np.bincount(ring["mesh/elem_body"])[grains] == 18)
    # No corner folds in the first 200 ns; on kite meshes one has folded by 100 ns (by 30 ns
    # when the potential law's field was each element's own)
    assert _folded(ring).max() == 0
    assert _folded(kite)[:11].max() > 0


def test_fast_ring_run_with_eos_same_bits_on_one_and_two_ranks(tmp_path):
    write_scene(tmp_path / "s.toml", _fast("r.h5", "ring", eos=True))
    a = same_bits_on_one_and_two_ranks("s.toml", tmp_path)
    assert np.abs(a["energy/balance_error"]).max() < 0.01


def test_prepare_refuses_ring_meshes(tmp_path):
    doc = small_prepare()
    doc["element"]["mesh"] = "ring"
    write_scene(tmp_path / "p.toml", doc)
    p = pdfem(["prepare", "p.toml", "-o", "bed.h5"], tmp_path, timeout=60)
    assert p.returncode == 2
    lines = p.stderr.strip().splitlines()
    assert len(lines) == 1 and "element.mesh" in lines[0] and "p.toml" in lines[0], p.stderr
    assert not (tmp_path / "bed.h5").exists()
