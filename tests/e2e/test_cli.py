"""The real command line: bit-identical run files on 1-4 ranks, bad scenes, output safety."""

import h5py
import numpy as np
import pytest

from tests.helpers import datasets, pdfem
from tests.scenes import drifting_grains, settling_bed, toml, write_scene


def test_bit_identical_on_1_2_3_4_ranks(tmp_path):
    write_scene(tmp_path / "s.toml", drifting_grains(n=16, end=3e-6, extra={
        "gravity": {"g": [0.0, -9.81e6]}, "damping": {"gamma": 1.0e5},
        "gauges": [{"name": "g", "point": [0.0015, 0.0015]}]}))
    ref = None
    for n in (1, 2, 3, 4):
        p = pdfem(["run", "s.toml", "-o", f"r{n}.h5", "--quiet"], tmp_path, ranks=n)
        assert p.returncode == 0, p.stderr
        d = datasets(tmp_path / f"r{n}.h5")
        if ref is None:
            ref = d
            assert len(ref["frames/time"]) >= 4
            continue
        assert sorted(d) == sorted(ref) and "gauges/g/velocity" in d
        for k in ref:
            assert np.array_equal(ref[k], d[k]), f"{k} differs on {n} ranks"


BAD = {
    "unknown table": "[nonsense]\nx = 1\n",
    "unknown key": "[time]\nend = 1e-6\nbogus = 2\n",
    "wrong type": "[time]\nend = 'soon'\n",
    "negative end": "[time]\nend = -1.0\n",
    "nan": "[time]\nend = nan\n",
    "safety above stable": "[time]\nend = 1e-6\nsafety = 1.5\n",
    "missing material": "[[grains]]\ncenter = [0.001, 0.001]\naxes = [1e-4, 1e-4]\n"
                        "material = 'steel'\n",
    "outside domain": "[[grains]]\ncenter = [-0.5, 0.001]\naxes = [1e-4, 1e-4]\n"
                      "material = 'grain'\n",
    "overlap": "[[grains]]\ncenter = [0.003, 0.003]\naxes = [4e-4, 4e-4]\nmaterial = 'grain'\n"
               "[[grains]]\ncenter = [0.0032, 0.003]\naxes = [4e-4, 4e-4]\nmaterial = 'grain'\n",
    "zero density": "[materials.soft]\ndensity = 0.0\nbulk = 1e9\nshear = 1e9\n",
    "bad rule": "[element]\nrule = '3x3'\n",
    "missing grains file": "[grains_file]\npath = 'nowhere.csv'\nmaterial = 'grain'\n",
    "bc on unknown body": "[[bc]]\nbody = 'anvil'\ntype = 'fixed'\n",
}


@pytest.mark.parametrize("case", sorted(BAD))
def test_bad_scene_one_line_exit_2(tmp_path, case):
    base = drifting_grains(n=2, end=1e-7)
    # Remove the table a fault redefines, then append the fault (TOML text) to the file
    if BAD[case].startswith("[time]"):
        del base["time"]
    if BAD[case].startswith("[element]"):
        del base["element"]
    (tmp_path / "bad.toml").write_text(toml(base) + "\n" + BAD[case])
    p = pdfem(["run", "bad.toml", "--quiet"], tmp_path)
    assert p.returncode == 2, (case, p.stdout, p.stderr)
    lines = p.stderr.strip().splitlines()
    assert len(lines) == 1 and "Traceback" not in p.stderr, p.stderr
    assert "bad.toml" in lines[0]
    assert not list(tmp_path.glob("*.h5*"))


def test_missing_scene_file_and_existing_output(tmp_path):
    p = pdfem(["run", "absent.toml"], tmp_path)
    assert p.returncode == 2 and "absent.toml" in p.stderr and "Traceback" not in p.stderr
    write_scene(tmp_path / "s.toml", drifting_grains(n=2, end=1e-7, out="keep.h5"))
    (tmp_path / "keep.h5").write_bytes(b"precious")
    p = pdfem(["run", "s.toml", "--quiet"], tmp_path)
    assert p.returncode == 2 and "--force" in p.stderr
    assert (tmp_path / "keep.h5").read_bytes() == b"precious"
    p = pdfem(["run", "s.toml", "--quiet", "--force"], tmp_path)
    assert p.returncode == 0, p.stderr
    assert h5py.is_hdf5(tmp_path / "keep.h5")


def test_settling_bed_bit_identical_after_20000_steps(tmp_path):
    doc = settling_bed(n=200, end=1.0, partition="rcb")
    doc["time"]["max_steps"] = 20000
    # Every contact of each frame too (/contacts/<frame>)
    doc["output"].update(interval=5.0e-5, fields=["x", "v", "stress", "contacts"])
    write_scene(tmp_path / "bed.toml", doc)
    ref = None
    for n in (1, 2, 3, 4):
        p = pdfem(["run", "bed.toml", "-o", f"b{n}.h5", "--quiet"], tmp_path, ranks=n,
                  timeout=600)
        assert p.returncode == 0, p.stderr
        d = datasets(tmp_path / f"b{n}.h5")
        if ref is None:
            ref = d
            assert d["energy/contact"][-1] > 0 and len(d["frames/time"]) >= 4
            assert d[f"contacts/{len(d['frames/time']) - 1:06d}/key"].shape[0] > 100
            continue
        assert sorted(d) == sorted(ref)
        for k in ref:
            assert np.array_equal(ref[k], d[k]), f"{k} differs on {n} ranks"


def test_heated_bed_bit_identical_on_1_2_3_ranks(tmp_path):
    """Contact heat (conductance, friction) into grains and the floor is rank-count free."""
    heat = {"heat": {"initial": 300.0}, "conduction": {}, "contact_conductance": {"h": 1.0e9},
            "friction_heating": {}, "thermal_expansion": {}, "thermoelastic": {}}
    doc = settling_bed(n=60, cols=10, end=8.0e-6, g=-1.0e7, partition="rcb", extra=heat)
    doc["materials"]["grain"].update(specific_heat=1000.0, conductivity=0.4, expansion=5.0e-5)
    write_scene(tmp_path / "hot.toml", doc)
    ref = None
    for n in (1, 2, 3):
        p = pdfem(["run", "hot.toml", "-o", f"h{n}.h5", "--quiet"], tmp_path, ranks=n)
        assert p.returncode == 0, p.stderr
        d = datasets(tmp_path / f"h{n}.h5")
        if ref is None:
            ref = d
            # Friction heated the bed: the temperature rose somewhere
            assert d["frames/temperature"][-1].max() > 300.0
            assert d["energy/friction"][-1] > 0.0
            continue
        for k in ref:
            assert np.array_equal(ref[k], d[k]), f"{k} differs on {n} ranks"
