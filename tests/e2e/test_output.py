"""Run-file contents, the XDMF sidecar and meshio export through the command line."""

import xml.etree.ElementTree as ET

import h5py
import meshio
import numpy as np
import pytest

from tests.helpers import pdfem
from tests.scenes import settling_bed, write_scene


@pytest.fixture(scope="module")
def run_file(tmp_path_factory):
    """A settling bed with contact forces in the frames, 2x2 elements, on 2 ranks."""
    d = tmp_path_factory.mktemp("out")
    doc = settling_bed(n=30, cols=10, end=1.0)
    doc["time"]["max_steps"] = 8000
    doc["output"].update(interval=1.0e-5, fields=["x", "v", "stress", "contact_force"])
    doc["element"]["rule"] = "2x2"
    write_scene(d / "s.toml", doc)
    p = pdfem(["run", "s.toml", "-o", "r.h5", "--quiet"], d, ranks=2)
    assert p.returncode == 0, p.stderr
    return d / "r.h5"


def test_frames_hold_the_requested_fields(run_file):
    with h5py.File(run_file) as f:
        fr = f["frames"]
        nf, nn, ne = fr["time"].shape[0], f["mesh/node_body"].shape[0], f["mesh/conn"].shape[0]
        assert nf >= 3
        assert fr["x"].shape == (nf, nn, 2) and fr["contact_force"].shape == (nf, nn, 2)
        assert fr["stress"].shape == (nf, ne, 4, 4) and fr["stress_cell"].shape == (nf, ne, 4)
        assert np.allclose(fr["stress_cell"][-1], fr["stress"][-1].mean(axis=1), rtol=1e-12,
                           atol=0.0)
        # The bed has settled onto the floor: contacts push
        assert np.abs(fr["contact_force"][...]).max() > 0
        assert "scene" in f.attrs and "effects" in f.attrs


def test_xdmf_points_at_existing_datasets(run_file):
    xdmf = run_file.with_suffix(".xdmf")
    root = ET.parse(xdmf).getroot()
    grids = root.findall(".//Grid[@GridType='Uniform']")
    with h5py.File(run_file) as f:
        assert len(grids) == f["frames/time"].shape[0]
        nitems = 0
        for item in root.iter("DataItem"):
            if item.get("Format") != "HDF":
                continue
            fname, path = item.text.strip().split(":")
            assert fname == run_file.name
            dims = tuple(int(n) for n in item.get("Dimensions").split())
            assert f[path].shape == dims, path
            nitems += 1
        assert nitems > 0
        # Each hyperslab selects as many values as its outer item declares
        for slab in root.iter("DataItem"):
            if slab.get("ItemType") != "HyperSlab":
                continue
            sel = [int(v) for v in slab[0].text.split()]
            count = sel[2 * len(sel) // 3:]
            assert int(np.prod(count)) == int(np.prod([int(n) for n in
                                                       slab.get("Dimensions").split()]))
        names = {a.get("Name") for a in grids[0].findall("Attribute")}
        assert {"stress_yy", "v_x", "contact_force_y"} <= names


def test_vtu_export_reads_back_with_the_same_numbers(run_file):
    p = pdfem(["export", run_file.name, "--frames", "last", "-p", "e"], run_file.parent)
    assert p.returncode == 0, p.stderr
    with h5py.File(run_file) as f:
        k = f["frames/time"].shape[0] - 1
        m = meshio.read(run_file.parent / f"e-{k:04d}.vtu")
        assert np.array_equal(m.points[:, :2], f["frames/x"][k])
        assert np.array_equal(m.point_data["v"], f["frames/v"][k])
        assert np.array_equal(m.cell_data["stress"][0], f["frames/stress_cell"][k])
        assert np.array_equal(m.cells_dict["quad"], f["mesh/conn"][...])


def test_xdmf_export_through_meshio(run_file):
    p = pdfem(["export", run_file.name, "--format", "xdmf", "--frames", "0,1", "-p", "ts"],
              run_file.parent)
    assert p.returncode == 0, p.stderr
    r = meshio.xdmf.TimeSeriesReader(str(run_file.parent / "ts.xdmf"))
    pts, _ = r.read_points_cells()
    t, pd, cd = r.read_data(1)
    with h5py.File(run_file) as f:
        assert t == f["frames/time"][1]
        assert np.array_equal(cd["stress_yy"][0], f["frames/stress_cell"][1][:, 1])


@pytest.mark.parametrize("args,msg", [
    (["export", "nothing.h5"], "nothing.h5: no such run file"),
    (["export", "r.h5", "--frames", "999"], "--frames: frame 999 out of range"),
    (["export", "r.h5", "--frames", "x"], "--frames: expected all, last or indices"),
])
def test_bad_export_input(run_file, args, msg):
    p = pdfem(args, run_file.parent)
    assert p.returncode == 2 and msg in p.stderr, p.stderr
