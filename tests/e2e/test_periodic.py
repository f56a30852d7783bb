"""Periodic sides through the real command line: a strip pressed by a hammer that drags its
grains across the seam is the same strip wherever the seam cuts it, bit-identical on 1 to 4
ranks and after a restart, and a scene that cannot be periodic is refused in one line."""

import h5py
import numpy as np
import pytest

from tests.helpers import datasets, pdfem
from tests.scenes import periodic_press, prep_scene, shock_scene, write_scene


@pytest.fixture(scope="module")
def press(tmp_path_factory):
    """The periodic press on 1 rank (its run file's datasets)."""
    d = tmp_path_factory.mktemp("press")
    write_scene(d / "p.toml", periodic_press())
    p = pdfem(["run", "p.toml", "--quiet"], d)
    assert p.returncode == 0, p.stderr
    return datasets(d / "press.h5")


def test_the_seam_can_cut_the_strip_anywhere(tmp_path, press):
    # The same grains two block elements (0.4 mm) farther right, wrapped into the box: other
    # grains lie across the seam and meet the blocks' other ends, yet energies and the
    # hammer's load agree to rounding (the seam and the tied block columns add nothing)
    write_scene(tmp_path / "q.toml", periodic_press(shift=4.0e-4, out="q.h5"))
    p = pdfem(["run", "q.toml", "--quiet"], tmp_path)
    assert p.returncode == 0, p.stderr
    q = datasets(tmp_path / "q.h5")
    for k in ("energy/kinetic", "energy/strain", "energy/contact", "energy/plastic",
              "energy/friction", "gauges/hammer/force"):
        a, b = press[k], q[k]
        assert np.abs(a - b).max() <= 1e-8 * np.abs(a).max(), k
    # The hammer loaded the bed, and grains lie across the seam in both runs
    assert press["energy/plastic"][-1] > 0.05 * press["energy/kinetic"][0]
    for d in (press, q):
        x, body = d["frames/x"][-1], d["mesh/node_body"]
        across = [g for g in range(8) if x[body == g, 0].min() < 0.0 < x[body == g, 0].max()
                  or x[body == g, 0].min() < 1.2e-3 < x[body == g, 0].max()]
        assert across, "no grain lies across the seam"


def test_periodic_strip_is_bit_identical_on_1_2_3_4_ranks(tmp_path, press):
    write_scene(tmp_path / "p.toml", periodic_press())
    for n, part in ((2, "strips"), (3, "strips"), (4, "rcb")):
        doc = periodic_press(out=f"r{n}.h5")
        doc["domain"]["partition"] = part
        write_scene(tmp_path / f"p{n}.toml", doc)
        p = pdfem(["run", f"p{n}.toml", "--quiet"], tmp_path, ranks=n)
        assert p.returncode == 0, p.stderr
        d = datasets(tmp_path / f"r{n}.h5")
        assert sorted(d) == sorted(press)
        for k in press:
            if k != "scene":
                assert np.array_equal(press[k], d[k]), f"{k} differs on {n} ranks"


def test_periodic_restart_is_bit_identical(tmp_path, press):
    # Checkpoints of a 2-rank run continued on 1 rank: the later frames and the energy series
    # are the uninterrupted run's
    doc = periodic_press(out="a.h5")
    doc["output"]["checkpoint_interval"] = 2.0e-7
    write_scene(tmp_path / "a.toml", doc)
    p = pdfem(["run", "a.toml", "--quiet"], tmp_path, ranks=2)
    assert p.returncode == 0, p.stderr
    p = pdfem(["run", "a.toml", "--restart", "a.h5.ckpt.h5", "-o", "b.h5", "--quiet"],
              tmp_path)
    assert p.returncode == 0, p.stderr
    b = datasets(tmp_path / "b.h5")
    nb = b["frames/time"].shape[0] - 1
    assert nb >= 1
    for k in ("frames/time", "frames/x", "frames/v", "frames/stress"):
        assert np.array_equal(press[k][-nb:], b[k][1:]), k
    for k in press:
        if k.startswith("energy/"):
            assert np.array_equal(press[k], b[k]), k


def test_a_bed_rained_between_periodic_sides_runs_periodic(tmp_path):
    # The rain route runs the solver with the scene's sides: grains that drift out through one
    # side are written as their image inside the box, and the bed runs with periodic sides
    prep = prep_scene(grains=12, width=1.2e-3, height=2.0e-3, phase_time=5.0e-4)
    prep["domain"]["periodic"] = "x"
    prep["walls"] = {"bottom": "none"}
    prep["bc"] = [b for b in prep["bc"] if "wall" not in b]
    write_scene(tmp_path / "prep.toml", prep)
    p = pdfem(["prepare", "prep.toml"], tmp_path)
    assert p.returncode == 0, p.stderr
    with h5py.File(tmp_path / "bed.h5") as f:
        centre = f["grains/nodes"][()].mean(axis=1)
    assert centre.shape[0] == 12 and np.all((centre[:, 0] >= 0.0) & (centre[:, 0] < 1.2e-3))
    top = float(h5py.File(tmp_path / "bed.h5")["grains/nodes"][()][:, :, 1].max())
    doc = shock_scene("bed.h5", top + 2.0e-5, width=1.2e-3, height=top + 4.0e-4, end=1.0e-7)
    doc["domain"]["periodic"] = "x"
    del doc["walls"]
    doc["bc"] = [b for b in doc["bc"] if "wall" not in b]
    for b in doc["blocks"]:
        b["nx"] = 4
    write_scene(tmp_path / "shock.toml", doc)
    p = pdfem(["run", "shock.toml", "--quiet"], tmp_path)
    assert p.returncode == 0, p.stderr


def _hot_press(shift, out):
    """The press with heat from plastic work and friction, conducted in every body; the steel
    conducts 2e5 W/m K, so that in 0.6 us heat spreads through the blocks, across their seam."""
    doc = periodic_press(shift=shift, out=out)
    doc["materials"]["hmx"].update(specific_heat=1444.0, conductivity=0.31)
    doc["materials"]["steel"].update(specific_heat=460.0, conductivity=2.0e5)
    for key in ("heat", "conduction", "dissipation_heating", "friction_heating"):
        doc[key] = {}
    return doc


def test_heat_crosses_the_seam_of_a_periodic_block(tmp_path):
    # Heat made where the grains press and rub on the hammer spreads through it: a block's tied
    # columns keep one temperature in every frame, the seam moved by 0.4 mm changes neither the
    # energies nor the grains' temperatures beyond rounding, and 2 ranks give 1 rank's bits
    runs = {}
    for name, shift, ranks in (("a", 0.0, 1), ("b", 4.0e-4, 1), ("a2", 0.0, 2)):
        write_scene(tmp_path / f"{name}.toml", _hot_press(shift, f"{name}.h5"))
        p = pdfem(["run", f"{name}.toml", "--quiet"], tmp_path, ranks=ranks)
        assert p.returncode == 0, p.stderr
        runs[name] = datasets(tmp_path / f"{name}.h5")
    a, b = runs["a"], runs["b"]
    assert all(np.array_equal(a[k], runs["a2"][k]) for k in a if k != "scene")
    for k in [k for k in a if k.startswith("energy/")] + ["gauges/hammer/force"]:
        assert np.abs(a[k] - b[k]).max() <= 1e-8 * max(np.abs(a[k]).max(), 1e-300), k
    body, x0 = a["mesh/node_body"], a["frames/x"][0]
    grain = body < 8
    rise = a["frames/temperature"] - a["frames/temperature"][0]
    assert np.abs(rise[:, grain] - (b["frames/temperature"] - b["frames/temperature"][0])[
        :, grain]).max() <= 1e-8 * rise.max()
    for blk in (8, 9):
        left = np.nonzero((body == blk) & (x0[:, 0] == 0.0))[0]
        right = np.nonzero((body == blk) & (x0[:, 0] == 1.2e-3))[0]
        right = right[np.argsort(x0[right, 1])]
        left = left[np.argsort(x0[left, 1])]
        assert left.size == right.size > 0
        assert np.array_equal(a["frames/temperature"][:, left], a["frames/temperature"][:, right])
    # The hammer was heated, and conduction carried heat across its seam
    hammer = body == 9
    assert rise[-1, hammer].max() > 0.0
    seam = (hammer) & (x0[:, 0] == 0.0)
    assert rise[-1, seam].max() > 1e-3 * rise[-1, hammer].max()


def _walls(d):
    d["walls"] = {"left": "frictionless"}


def _wall_bc(d):
    d["bc"].append({"wall": "right", "type": "roller"})


def _side_nodes(d):
    d["bc"].append({"body": "hammer", "nodes": "left", "type": "roller", "dof": "x"})


def _short_block(d):
    d["blocks"][0]["box"][2] = 1.0e-3


def _coarse_block(d):
    d["blocks"][1]["nx"] = 2


def _narrow(d):
    d["domain"]["cell_size"] = 5.0e-4


def _geometric(d):
    d["prepare"] = {"method": "geometric", "packing": 0.6, "height": 4.0e-4, "seed": 1,
                    "semi_axis": [1.0e-4, 1.2e-4], "aspect": [0.7, 1.0], "material": "hmx",
                    "output": "bed.h5"}


@pytest.mark.parametrize("edit, key", [
    (_walls, "walls.left"), (_wall_bc, "bc[1].wall"), (_side_nodes, "bc[1].nodes"),
    (_short_block, "blocks[0].box"), (_coarse_block, "blocks[1].nx"),
    (_narrow, "domain.box"), (_geometric, "prepare.method")])
def test_a_scene_that_cannot_be_periodic_is_refused(tmp_path, edit, key):
    doc = periodic_press()
    edit(doc)
    write_scene(tmp_path / "s.toml", doc)
    p = pdfem(["run", "s.toml"], tmp_path)
    assert p.returncode == 2
    lines = p.stderr.strip().splitlines()
    assert len(lines) == 1 and f"s.toml: {key}:" in lines[0] and "Traceback" not in p.stderr
    assert sorted(f.name for f in tmp_path.iterdir()) == ["s.toml"]
