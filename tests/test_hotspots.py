"""Hot-spot census (pdfem hotspots) on hand-built run files with known answers."""

import json

import h5py
import numpy as np
import pytest

from pdfem.cli import main
from pdfem.tools.analysis.hotcensus import census
from pdfem.tools.analysis.hotfront import FrontRelative, arrival_times, front_history
from pdfem.tools.analysis.hotgeom import components, segment_distance
from pdfem.tools.analysis.hotspots import weighted_percentiles
from pdfem.tools.analysis.runfile import read_run
from tests import test_shock_analysis as sa

A = 1.0e-4          # element side
N = 4               # a grain is N x N square elements
COLD = 293.15
RHO = {"hmx": 1900.0, "dense": 3800.0, "steel": 7850.0}
MECHS = ("plastic", "friction", "thermoelastic", "conducted")
SCENE = """
[domain]
box = [0.0, -1.0e-4, 1.4e-3, 5.0e-4]
[materials.hmx]
density = 1900.0
[materials.dense]
density = 3800.0
[materials.steel]
density = 7850.0
"""


def _grain(x0, y0, base, n=N, ny=None):
    """Nodes and counter-clockwise connectivity of a block of n x ny square elements."""
    ny = n if ny is None else ny
    return (sa._block_nodes(x0, y0, x0 + n * A, y0 + ny * A, n, ny),
            sa._block_conn(n, ny, base))


def _bed(shift_b=0.0):
    """Grains A (0..4a) and B (4a..8a, touching A, moved right by ``shift_b``) of hmx, C
    (10a..14a) of a material twice as dense, on a steel block 14 x 1 elements below."""
    parts = [(0.0, 0.0, N, N), (N * A + shift_b, 0.0, N, N), (10 * A, 0.0, N, N),
             (0.0, -A, 14, 1)]
    x, conn, base = [], [], 0
    for x0, y0, nx, ny in parts:
        xn, c = _grain(x0, y0, base, nx, ny)
        x.append(xn)
        conn.append(c)
        base += len(xn)
    return np.vstack(x), np.vstack(conn)


def elem(grain, i, j):
    """Element id of element (i, j) of grain 0 (A), 1 (B) or 2 (C)."""
    return grain * N * N + i + N * j


# Frames: 0 cold; 1 two patches (C interior 2x2, A's top-left corner); 2 a patch across the
# A-B contact plus a free-surface element of A; 3 C's bottom element on the steel block;
# 4 frame 2's temperatures with B moved half an element away
PATCH_C = [elem(2, 1, 1), elem(2, 2, 1), elem(2, 1, 2), elem(2, 2, 2)]
HOT = [
    {},
    {PATCH_C[0]: 800.0, PATCH_C[1]: 800.0, PATCH_C[2]: 800.0, PATCH_C[3]: 900.0,
     elem(0, 0, 3): 700.0},
    {elem(0, 3, 2): 650.0, elem(1, 0, 2): 750.0, elem(0, 1, 3): 600.0},
    {elem(2, 1, 0): 700.0},
    {elem(0, 3, 2): 650.0, elem(1, 0, 2): 750.0, elem(0, 1, 3): 600.0},
]


def make_bed_run(path, heat=True, temperature="element"):
    """The hand-built run file of the frames above (no [shock] table)."""
    x0, conn = _bed()
    ne, nf = len(conn), len(HOT)
    x = np.stack([_bed(0.5 * A if k == 4 else 0.0)[0] for k in range(nf)])
    temp = np.full((nf, ne), COLD)
    for k, hot in enumerate(HOT):
        for e, t in hot.items():
            temp[k, e] = t
    elem_body = np.repeat([0, 1, 2, 3], [N * N, N * N, N * N, 14])
    with h5py.File(path, "w") as f:
        f.attrs["scene"] = SCENE
        f["mesh/conn"], f["mesh/elem_body"] = conn, elem_body
        f["mesh/node_body"] = np.repeat([0, 1, 2, 3], [25, 25, 25, 30])
        f["mesh/elem_material"] = np.repeat([0, 0, 1, 2], [N * N, N * N, N * N, 14])
        f["mesh/body_kind"] = np.array([0, 0, 0, 1], np.int8)
        f["frames/time"] = np.arange(nf) * 1e-7
        f["frames/x"] = x
        if temperature == "element":
            f["frames/element_temperature"] = temp
        if heat:
            h = np.zeros((len(MECHS), nf, ne))
            # Frame 1: C's patch heated by plastic work, A's corner by friction
            h[:, 1, PATCH_C] = np.array([2.0, 0.5, 0.1, -0.6])[:, None]
            h[:2, 1, elem(0, 0, 3)] = [1.0, 3.0]
            for m, a in zip(MECHS, h, strict=True):
                f[f"frames/heat_{m}"] = a
    return path


def _spots(result, k):
    return [s for s in result["spots"] if s["frame"] == k]


def test_weighted_percentiles_closed_form():
    """The inverse of the mass-weighted distribution: repeated values for integer masses,
    numpy's weighted inverted_cdf for real ones, and a two-level bed by hand."""
    rng = np.random.default_rng(3)
    v, m = rng.normal(400.0, 50.0, 200), rng.integers(1, 6, 200)
    ps = [0.0, 10.0, 50.0, 90.0, 99.0, 99.9, 100.0]
    assert np.array_equal(weighted_percentiles(v, m, ps),
                          np.percentile(np.repeat(v, m), ps, method="inverted_cdf"))
    w = rng.uniform(0.1, 2.0, 200)
    assert np.allclose(weighted_percentiles(v, w, ps[1:]),
                       np.percentile(v, ps[1:], weights=w, method="inverted_cdf"))
    # 70 % of the mass at 300 K, 30 % at 800 K: 300 up to the 70th percentile, 800 above
    got = weighted_percentiles([800.0, 300.0, 300.0], [3.0, 4.0, 3.0], [50, 69.9, 70.1, 99])
    assert list(got) == [300.0, 300.0, 800.0, 800.0]
    assert np.isnan(weighted_percentiles([], [], [50])).all()


def test_front_relative_bins_on_uneven_frames():
    """Frames a little uneven: each element still gives one sample per bin, and a bin's
    time is its samples' mean time since arrival."""
    rng = np.random.default_rng(5)
    t = np.arange(40) * 1e-8 + rng.uniform(-1e-10, 1e-10, 40)
    t[0] = 0.0
    ta = rng.uniform(0.0, 2e-7, 300)
    fr = FrontRelative(t, ta, np.arange(300), np.ones(300))
    for k in range(40):
        fr.add(k, COLD + RATE * np.maximum(t[k] - ta, 0.0))
    h = fr.result()
    first = np.searchsorted(t, ta)
    assert max(h["n"]) == 300 and h["frames"] == list(range(-first.max(), 40 - first.min()))
    j = h["frames"].index(3)
    assert h["tau"][j] == pytest.approx(np.mean(t[first + 3] - ta))
    assert h["mean"][j] == pytest.approx(COLD + RATE * h["tau"][j])


def test_geometry_helpers():
    """Segment distances and connected components on small cases."""
    z = np.zeros((1, 2))
    d = segment_distance(z, np.array([[1.0, 0.0]]), np.array([[0.5, 0.3]]),
                         np.array([[2.0, 0.3]]))
    assert d[0] == pytest.approx(0.3)
    assert segment_distance(z, np.array([[1.0, 1.0]]), np.array([[0.0, 1.0]]),
                            np.array([[1.0, 0.0]]))[0] == 0.0
    lab = components(6, np.array([[0, 3], [3, 4], [1, 2]]))
    assert list(lab) == [0, 1, 1, 0, 0, 5]


def test_two_patches_sites_mechanisms_and_distribution(tmp_path):
    """Two hot patches in a cold bed: exactly two spots of the right areas and peaks; the
    interior and corner sites; the mechanisms and shares; the mass-weighted distribution
    and area fractions against a hand computation."""
    res, _ = census(make_bed_run(str(tmp_path / "bed.h5")), spot_threshold=500.0)
    assert _spots(res, 0) == [] and res["regions"] == ["whole"] and res["front"] is None
    one = _spots(res, 1)
    assert len(one) == 2
    c, a = one
    assert (c["id"], c["n_elements"], a["id"], a["n_elements"]) == (1, 4, 2, 1)
    assert c["area"] == pytest.approx(4 * A * A) and a["area"] == pytest.approx(A * A)
    assert c["diameter"] == pytest.approx(np.sqrt(16 * A * A / np.pi))
    assert (c["peak"], a["peak"]) == (900.0, 700.0) and c["mean"] == pytest.approx(825.0)
    assert c["centroid"] == pytest.approx([12 * A, 2 * A])
    assert a["centroid"] == pytest.approx([0.5 * A, 3.5 * A])
    assert (c["site"], a["site"]) == ("interior", "corner")
    assert c["mechanism"] == "plastic" and a["mechanism"] == "friction"
    assert [c["shares"][m] for m in MECHS] == pytest.approx([1.0, 0.25, 0.05, -0.3])
    assert [a["shares"][m] for m in MECHS] == pytest.approx([0.25, 0.75, 0.0, 0.0])
    # 48 grain elements; C's are twice as heavy: the whole bed weighs 64 hmx elements, of
    # which 55 are cold, one at 700 K, two (C's) at 800 K each and C's 800, 900 K pairs
    w = res["frames"][1]["whole"]
    m1 = RHO["hmx"] * A * A
    assert w["mass"] == pytest.approx(64 * m1) and w["n_elements"] == 48
    assert w["mean"] == pytest.approx((55 * COLD + 700 + 2 * (3 * 800 + 900)) / 64)
    assert (w["p50"], w["p90"], w["p99"], w["p99.9"], w["max"]) == \
        (COLD, 800.0, 900.0, 900.0, 900.0)
    assert w["area_fraction"][500.0] == pytest.approx(5 / 48)
    assert w["area_fraction"][400.0] == pytest.approx(5 / 48)
    assert w["area_fraction"][600.0] == pytest.approx(5 / 48)
    assert w["n_spots"] == 2 and w["spot_area"] == pytest.approx(5 * A * A)
    assert (w["max_spot_diameter"], w["max_spot_peak"]) == (c["diameter"], 900.0)


def test_patch_across_a_contact_is_one_spot(tmp_path):
    """A patch spanning grains A and B across their contact is one spot (site contact);
    moved apart by half an element the two halves are two free-surface spots; an element
    on the steel block is at a contact too."""
    res, _ = census(make_bed_run(str(tmp_path / "bed.h5"), heat=False))
    two = _spots(res, 2)
    assert [(s["n_elements"], s["n_grains"], s["site"]) for s in two] == \
        [(2, 2, "contact"), (1, 1, "surface")]
    assert two[0]["area"] == pytest.approx(2 * A * A) and two[0]["peak"] == 750.0
    assert two[0]["mechanism"] == "unknown"
    assert [s["site"] for s in _spots(res, 3)] == ["contact"]
    apart = _spots(res, 4)
    assert len(apart) == 3 and {s["site"] for s in apart} == {"surface"}
    assert any("unknown" in n for n in res["notes"])


def test_node_temperatures_are_averaged_onto_elements(tmp_path):
    """Without element_temperature the element's temperature is its nodes' mean: one hot
    node inside grain C makes a spot of its four elements at a quarter of the excess."""
    path = make_bed_run(str(tmp_path / "bed.h5"), temperature="node")
    with h5py.File(path, "a") as f:
        t = np.full((5, 105), COLD)
        t[1, 50 + 2 + 5 * 2] = COLD + 400.0          # C's centre node
        f["frames/temperature"] = t
    res, _ = census(path, thresholds=(350.0,), spot_threshold=350.0)
    assert res["temperature_field"] == "temperature"
    (s,) = _spots(res, 1)
    assert s["n_elements"] == 4 and s["peak"] == pytest.approx(COLD + 100.0)


def _shock_run(path):
    """The steady synthetic wave of test_shock_analysis, every grain heating at RATE from
    the time the exact front Y_TOP - US t reaches its initial centroid."""
    sa.make_run(path)
    with h5py.File(path, "a") as f:
        t, x0, conn = f["frames/time"][:], f["frames/x"][0], f["mesh/conn"][:]
        ta = (sa.Y_TOP - x0[conn, 1].mean(axis=1)) / sa.US
        f["frames/element_temperature"] = COLD + RATE * np.maximum(t[:, None] - ta, 0.0)
    return ta


RATE = 1.0e8        # K/s: 100 K per microsecond since the front passed


def test_shock_run_regions_and_front_relative_history(tmp_path):
    """Behind the front as analyse defines it; arrival times within a row's crossing time
    of the exact front's; the front-relative mean follows COLD + RATE tau."""
    path = str(tmp_path / "shock.h5")
    ta = _shock_run(path)
    res, _ = census(path)
    run = read_run(path)
    fh = front_history(run)
    ng = run.ng
    assert res["regions"] == ["whole", "shocked"]
    for k, fr in enumerate(res["frames"]):
        assert fr["whole"]["n_elements"] == ng
        assert fr["shocked"]["n_elements"] == int(fh["shocked"][k].sum())
    x0 = run.grain_y[0]
    tol = 1.1 * sa.S / sa.US
    assert np.max(np.abs(arrival_times(run.time, fh["y_f"], x0) - ta[:ng])) < tol
    h = res["front_relative"]
    assert h["n_elements"] == ng and h["dt"] == pytest.approx(run.time[1] - run.time[0])
    tau, mean, n = (np.array(h[k]) for k in ("tau", "mean", "n"))
    assert n.max() == ng and np.all(np.diff(h["frames"]) == 1)
    ok = (tau > tol) & (n >= 10)
    assert ok.sum() > 50
    assert np.all(np.abs(mean[ok] - (COLD + RATE * tau[ok])) < RATE * tol)
    assert np.all(np.array(h["p99"])[ok] >= mean[ok])
    assert np.allclose(np.array(h["mean"])[tau < -tol], COLD)
    last = res["frames"][-1]
    assert last["shocked"]["mean"] > last["whole"]["mean"] - 1e-9


def test_cli_writes_csv_json_and_plots(tmp_path, capsys):
    """pdfem hotspots end to end: the CSVs, the JSON, the figures, the report on stdout."""
    path = make_bed_run(str(tmp_path / "bed.h5"))
    assert main(["hotspots", path, "--thresholds", "400, 600", "--spot-threshold",
                 "500"]) == 0
    assert "Hot-spot census" in capsys.readouterr().out
    js = json.loads((tmp_path / "bed-hotspots.json").read_text())
    assert js["settings"]["thresholds"] == [400.0, 600.0] and len(js["frames"]) == 5
    rows = (tmp_path / "bed-hotspots.csv").read_text().splitlines()
    assert len(rows) == 1 + 5 and "area_fraction_above_600K" in rows[0]
    spots = (tmp_path / "bed-hotspots-spots.csv").read_text().splitlines()
    assert len(spots) == 1 + len(js["spots"]) and "share_friction" in spots[0]
    assert spots[1].split(",")[7:9] == ["interior", "plastic"]
    for name in ("map", "distribution", "count"):
        assert (tmp_path / f"bed-hotspots-{name}.png").read_bytes()[:4] == b"\x89PNG"
    assert not (tmp_path / "bed-hotspots-front.csv").exists()
    assert main(["hotspots", path, "-o", str(tmp_path / "n"), "--plots", "none"]) == 0
    assert sorted(p.name for p in tmp_path.glob("n-*")) == \
        ["n-hotspots-spots.csv", "n-hotspots.csv", "n-hotspots.json"]
    # A shock run: the front-relative CSV and figure too, here as PDF
    _shock_run(str(tmp_path / "shock.h5"))
    assert main(["hotspots", str(tmp_path / "shock.h5"), "-o", str(tmp_path / "s"),
                 "--plots", "pdf"]) == 0
    front = (tmp_path / "s-hotspots-front.csv").read_text().splitlines()
    assert front[0].startswith("frames_since_arrival,time_since_arrival,n_elements")
    assert len(front) > 50
    for name in ("map", "distribution", "count", "front"):
        assert (tmp_path / f"s-hotspots-{name}.pdf").read_bytes()[:4] == b"%PDF"
    assert not list(tmp_path.glob("*.part"))


@pytest.mark.parametrize("case", ["no_temperature", "heat_shape", "thresholds", "plots",
                                  "exists", "missing"])
def test_cli_bad_input_one_line_exit_2(tmp_path, capsys, case):
    """Bad input: one line naming the file or option, exit status 2, nothing overwritten."""
    path = make_bed_run(str(tmp_path / "bed.h5"))
    args = ["hotspots", path, "--plots", "none"]
    want = {"no_temperature": "add \"element_temperature\" or \"temperature\" to output.fields",
            "heat_shape": "/frames/heat_plastic", "thresholds": "--thresholds",
            "plots": "--plots", "exists": "exists (use --force", "missing": "no such run file"}
    if case == "no_temperature":
        with h5py.File(path, "a") as f:
            del f["frames/element_temperature"]
    elif case == "heat_shape":
        with h5py.File(path, "a") as f:
            del f["frames/heat_plastic"]
            f["frames/heat_plastic"] = np.zeros((5, 3))
    elif case == "thresholds":
        args += ["--thresholds", "400,,600"]
    elif case == "plots":
        args[-1] = "svg"
    elif case == "exists":
        (tmp_path / "bed-hotspots.json").write_text("keep")
    else:
        args[1] = str(tmp_path / "nope.h5")
    capsys.readouterr()
    assert main(args) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and err.startswith("pdfem: error: ") and want[case] in err
    if case == "exists":
        assert (tmp_path / "bed-hotspots.json").read_text() == "keep"
    assert not (tmp_path / "bed-hotspots.csv").exists()
