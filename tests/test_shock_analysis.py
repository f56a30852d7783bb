"""Shock analysis (pdfem.tools.analysis) on synthetic data with a known answer."""

import json

import h5py
import numpy as np
import pytest

from pdfem.errors import InputError
from pdfem.tools.analysis import analyse
from pdfem.tools.analysis import front as fr
from pdfem.tools.analysis.plots import sweep_plot

# Steady snowplow-like wave: bed density, density behind the front, particle velocity
RHO_S, RHO0, RHO1, UP = 1900.0, 1240.0, 1800.0, 288.0
US = UP / (1.0 - RHO0 / RHO1)
A = 1.0e-4                      # grain side (two square grains per row)
S = A * RHO_S / RHO0            # row spacing giving rho0
NROW = 40
W = 2 * A
Y_A = 2.0e-4                    # anvil face
H0 = NROW * S
Y_TOP = Y_A + H0
SIGMA = RHO0 * US * UP
T_ARR = H0 / US


def _square(cx, cy, hx, hy):
    """Corners (4, 2) of a rectangle, counter-clockwise."""
    return np.array([[cx - hx, cy - hy], [cx + hx, cy - hy], [cx + hx, cy + hy],
                     [cx - hx, cy + hy]])


def _block_nodes(x0, y0, x1, y1, nx, ny):
    """Nodes of a block meshed nx by ny, node (i, j) at i + (nx + 1) j."""
    xs, ys = np.linspace(x0, x1, nx + 1), np.linspace(y0, y1, ny + 1)
    return np.array([[x, y] for y in ys for x in xs])


def _block_conn(nx, ny, base):
    """Counter-clockwise connectivity of a block's elements."""
    return np.array([[base + i + (nx + 1) * j, base + i + 1 + (nx + 1) * j,
                      base + i + 1 + (nx + 1) * (j + 1), base + i + (nx + 1) * (j + 1)]
                     for j in range(ny) for i in range(nx)])


def _grain_centres(t):
    """Row centres (F, NROW) and downward velocities of the steady wave at times t."""
    # Row i (top at Y_TOP - i S) starts moving when the front passes its top
    y0 = Y_TOP - A / 2 - np.arange(NROW) * S
    hit = np.arange(NROW) * S / US
    moving = t[:, None] >= hit[None, :]
    y = np.where(moving, y0 - UP * (t[:, None] - hit), y0)
    return np.maximum(y, Y_A + A / 2), np.where(moving, UP, 0.0)


SCENE = """
[domain]
box = [0.0, 0.0, {w}, 0.01]
[materials.grain]
density = 1900.0
bulk = 12.7e9
shear = 4.4e9
[materials.steel]
density = 7850.0
[[blocks]]
name = "bottom"
box = [0.0, 0.0, {w}, {ya}]
nx = 2
ny = 1
material = "steel"
[[blocks]]
name = "hammer"
box = [0.0, {yt}, {w}, {yh}]
nx = 2
ny = 1
material = "steel"
[[bc]]
body = "hammer"
type = "velocity"
velocity = [0.0, -288.0]
"""
SHOCK = """
[shock]
hammer = "hammer"
anvil = "bottom"
hammer_gauge = "hammer"
anvil_gauge = "bottom"
solid_density = 1900.0
front_fraction = 0.5
plots = "png"
reference_us = 500.0
reference_arrival = 8e-6
reference_density = 1240.0
"""


def make_run(path, shock=True, nframes=161):
    """Write a synthetic run file of the steady wave; frames run to 1.05 arrival times."""
    t = np.linspace(0.0, 1.05 * T_ARR, nframes)
    yc, u = _grain_centres(t)
    ng = 2 * NROW
    # Nodes: grains (4 each, two per row), then the bottom and hammer blocks (6 each)
    nn = 4 * ng + 12
    x = np.zeros((nframes, nn, 2))
    v = np.zeros((nframes, nn, 2))
    for r in range(NROW):
        for c in range(2):
            g = 2 * r + c
            for k in range(nframes):
                x[k, 4 * g:4 * g + 4] = _square((c + 0.5) * A, yc[k, r], A / 2, A / 2)
            v[:, 4 * g:4 * g + 4, 1] = -u[:, r, None]
    x[:, 4 * ng:4 * ng + 6] = _block_nodes(0.0, 0.0, W, Y_A, 2, 1)
    hb = _block_nodes(0.0, Y_TOP, W, Y_TOP + 3e-4, 2, 1)
    x[:, 4 * ng + 6:] = hb[None] - np.outer(UP * t, [0.0, 1.0]).reshape(-1, 1, 2)
    v[:, 4 * ng + 6:, 1] = -UP
    conn = np.vstack([np.arange(4 * ng).reshape(ng, 4), _block_conn(2, 1, 4 * ng),
                      _block_conn(2, 1, 4 * ng + 6)])
    node_body = np.concatenate([np.repeat(np.arange(ng), 4), np.full(6, ng), np.full(6, ng + 1)])
    elem_body = np.concatenate([np.arange(ng), [ng, ng, ng + 1, ng + 1]])
    stress = np.zeros((nframes, len(conn), 1, 4))
    stress[:, :ng, 0, 1] = np.repeat(-SIGMA * (u > 0), 2, axis=1)
    # Gauges: the hammer face at sigma from the start, the anvil from the arrival on
    gt = np.linspace(0.0, t[-1], 4 * nframes)
    scene = SCENE.format(w=W, ya=Y_A, yt=Y_TOP, yh=Y_TOP + 3e-4) + (SHOCK if shock else "")
    with h5py.File(path, "w") as f:
        f.attrs["scene"] = scene
        f["mesh/conn"], f["mesh/node_body"], f["mesh/elem_body"] = conn, node_body, elem_body
        f["mesh/elem_material"] = np.concatenate([np.zeros(ng, int), np.ones(4, int)])
        f["mesh/body_kind"] = np.array([0] * ng + [1, 1], np.int8)
        f["frames/time"], f["frames/x"], f["frames/v"], f["frames/stress"] = t, x, v, stress
        f["gauges/time"] = gt
        for name, s, vg in (("hammer", -SIGMA * np.ones_like(gt), -UP),
                            ("bottom", -SIGMA * (gt >= T_ARR), 0.0)):
            f[f"gauges/{name}/velocity"] = np.outer(np.full(len(gt), vg), [0.0, 1.0])
            f[f"gauges/{name}/stress"] = np.outer(s, [0.0, 1.0, 0.0, 0.0])
            # The bed's push on the piston (up) and on the anvil (down), N/m
            f[f"gauges/{name}/force"] = np.outer(s * W * (1.0 if name == "bottom" else -1.0),
                                                 [0.0, 1.0])
        f["energy/time"] = t
        f["energy/balance_error"] = np.linspace(0.0, 1e-3, nframes)
    return path


def test_front_on_arrays():
    """Front positions (layer scan) and the per-grain first-passage fit of the steady wave."""
    t = np.linspace(0.0, 1.05 * T_ARR, 161)
    yc, u = _grain_centres(t)
    gm = np.full(NROW, RHO_S * A * W)
    hy = Y_TOP - UP * t
    fp = fr.front_positions(t, yc, -u, gm, hy, np.full_like(t, -UP), np.full_like(t, Y_A),
                            Y_TOP, layer=1.13 * A, fraction=0.5)
    # Within about a row spacing of the exact front Y_TOP - US t at every frame
    exact = np.maximum(Y_TOP - US * t, Y_A)
    assert fp["t_impact"] == 0.0 and np.max(np.abs(fp["y_f"] - exact)) < 1.1 * S
    # Row i is passed at i S / US, within a frame; its initial depth is A/2 + i S
    tp = fr.passage_times(t, -u, 0.5 * UP)
    assert np.all(np.abs(tp - np.arange(NROW) * S / US) <= t[1] - t[0])
    d0 = Y_TOP - yc[0]
    fit = fr.steady_front(d0, tp, H0, 0.1)
    assert fit["steadiness"] == "steady" and fit["us"] == pytest.approx(US, rel=0.01)
    assert fit["se"] < 0.01 * US and fit["missing"] == 0 and fit["passed"]
    assert fit["t_start"] == pytest.approx(0.15 * T_ARR, abs=2 * (t[1] - t[0]))
    y_line = Y_TOP - fit["us"] * (t - fit["t0"])
    frames = np.flatnonzero((t >= fit["t_start"]) & (t <= fit["t_end"]))
    st = fr.shocked_state(frames, yc, -u, gm, hy, np.full_like(t, -UP), y_line, W, 1.13 * A)
    assert st["up"] == pytest.approx(UP, rel=1e-9)
    assert st["rho1"] == pytest.approx(RHO1, rel=0.04)


def test_front_fit_tells_unsteady_and_stalled_fronts():
    """A front that slows to half its speed is not fitted; one that stops at 60 % of the
    bed is not either; a rough but steady one is fitted and said to be unresolved."""
    d0 = np.linspace(0.0, 1.0, 101)
    # Decelerating: 1000 m/s over the upper half, 500 below
    t = np.where(d0 < 0.5, d0 / 1000.0, 0.5 / 1000.0 + (d0 - 0.5) / 500.0)
    dec = fr.steady_front(d0, t, 1.0, 0.1)
    assert dec["steadiness"] == "unsteady" and np.isnan(dec["us"])
    assert "no steady front" in dec["reason"] and dec["us_late"] < dec["us_early"]
    # Stalled: nothing deeper than 60 % is ever passed
    stall = fr.steady_front(d0, np.where(d0 < 0.6, d0 / 1000.0, np.nan), 1.0, 0.1)
    assert np.isnan(stall["us"]) and "did not cross 85%" in stall["reason"]
    # Steady at 1000 m/s with a scatter of a quarter of the transit time in a few grains
    rng = np.random.default_rng(1)
    few = np.linspace(0.0, 1.0, 12)
    rough = fr.steady_front(few, few / 1000.0 + rng.normal(0.0, 2.5e-4, few.size), 1.0, 0.1)
    assert rough["steadiness"] == "unresolved" and np.isfinite(rough["us"])
    assert "steadiness not resolved" in rough["reason"]
    assert fr.front_fit(few, np.full(12, np.nan), 1.0)["reason"].startswith("only 0 grain")


def test_compaction_and_momentum_share():
    """Compaction from the centre of mass and from the bed height, kept share; the momentum
    of the grains ahead of the front; the drive's deviation; the piston's stress."""
    from pdfem.tools.analysis import compaction as cp

    t = np.linspace(0.0, 1.0, 11)
    # Two grains of mass 1 and 3 at heights 1 and 3 over an anvil at 0: compress to half,
    # then spring back to three quarters
    f = np.concatenate([np.linspace(1.0, 0.5, 6), np.linspace(0.55, 0.75, 5)])
    gy = np.stack([1.0 * f, 3.0 * f], axis=1)
    c = cp.compaction(t, gy, np.array([1.0, 3.0]), np.zeros(11), 4.0 * f, 4.0 * f, 4.0)
    assert c["peak"] == pytest.approx(0.5) and c["t_peak"] == pytest.approx(0.5)
    assert c["final"] == pytest.approx(0.25) and c["kept"] == pytest.approx(0.5)
    assert c["final_height"] == pytest.approx(0.25)
    vy = np.array([[-2.0, -1.0]] * 11)
    assert cp.momentum_ahead([3], gy, vy, np.array([1.0, 3.0]), np.full(11, 2.0)) == \
        pytest.approx(2.0 / 5.0)
    assert cp.drive_deviation(t, np.where(t < 0.5, -100.0, -90.0), 100.0, 0.6) == \
        pytest.approx(0.1)
    force = np.outer(np.full(11, 50.0), [0.0, 1.0])
    assert cp.piston_stress(t, t, force, 2.0, 0.2, 0.8) == pytest.approx(25.0)


def test_jump_closures_and_snowplow():
    """Closure formulas against a hand computation; the 1997 report's snowplow numbers."""
    jc = fr.jump_closures(1000.0, 2000.0, 500.0, 200.0, 1.2e8)
    assert jc["mass"] == pytest.approx(abs(1000 * 500 - 2000 * 300) / (1000 * 500))
    assert jc["mass_strain"] == pytest.approx(abs(200 / 500 - 0.5) / 0.5)
    assert jc["momentum"] == pytest.approx((1.2e8 - 1e8) / 1.2e8)
    sp = fr.snowplow(288.0, 1240.0, 1900.0)
    assert sp["us"] == pytest.approx(829.1, abs=1.0)
    assert sp["sigma"] == pytest.approx(1240.0 * sp["us"] * 288.0)
    assert sp["rho1"] == 1900.0
    assert np.isnan(fr.jump_closures(1000.0, 2000.0, 0.0, 0.0, 0.0)["mass"])
    assert fr.elastic_speed({"density": 1900.0, "bulk": 12.7e9, "shear": 4.4e9}) == \
        pytest.approx(np.sqrt((12.7e9 + 4.4e9 * 4 / 3) / 1900.0))
    assert np.isnan(fr.elastic_speed({"density": 1900.0}))


def test_bound_of_the_compacted_crystal():
    """The densest bed a front of stress sigma leaves: rho_s / ((1 - sigma/K)(1 - W)) with a
    linear bulk, rho_s / (1 - eta) on the crystal's Hugoniot (p_H(eta) = sigma), NaN where a
    linear bulk cannot hold sigma; the bound it puts on Us and rho1; the slowest front the
    sweep drives each piston for is its fixed point."""
    from pdfem.kernels.eos import hugoniot_pressure
    from pdfem.tools.study.hugoniot import slowest_front

    lin = {"model": "cap", "bulk": 12.7e9, "W": 0.01}
    assert fr.compacted_density(1.0e9, 1900.0, lin) == pytest.approx(
        1900.0 / ((1.0 - 1.0e9 / 12.7e9) * 0.99), rel=1e-14)
    assert np.isnan(fr.compacted_density(13.0e9, 1900.0, lin))
    eos = {"model": "elastic", "bulk": 12.7e9, "eos": "us_up", "eos_s": 2.29, "W": 0.5}
    rho = fr.compacted_density(6.0e9, 1900.0, eos)
    eta = 1.0 - 1900.0 / rho
    assert hugoniot_pressure(12.7e9, 2.29, eta) == pytest.approx(6.0e9, rel=1e-12)
    # Below V/V0 = 1 - 1/s at any stress
    assert 1900.0 < fr.compacted_density(1.0e12, 1900.0, eos) < 1900.0 / (1.0 - 1.0 / 2.29)
    b = fr.crystal_bound(1500.0, 6.0e9, 3300.0, 40.0, 1235.0, 2200.0, 1900.0, eos)
    assert b["rho1_max"] == pytest.approx(rho)
    assert b["us_min"] == pytest.approx(1500.0 / (1.0 - 1235.0 / rho)) and b["kept"]
    assert not fr.crystal_bound(1500.0, 6.0e9, 3300.0, 40.0, 1235.0, 1.01 * rho, 1900.0,
                                eos)["kept"]
    assert fr.crystal_bound(1500.0, 6.0e9, b["us_min"] - 41.0, 40.0, 1235.0, 2200.0,
                            1900.0, eos)["kept"] is False
    # No front fitted (an unsteady wave): nothing to check, which is not a broken bound
    from pdfem.tools.analysis.report import bound_word

    for us, up, rho1 in ((np.nan, np.nan, np.nan), (3300.0, 1500.0, np.nan)):
        none = fr.crystal_bound(up, 6.0e9, us, 40.0, 1235.0, rho1, 1900.0, eos)
        assert none["kept"] is None and none["rho1_max"] == pytest.approx(rho)
    assert [bound_word(k) for k in (True, False, None)] == ["kept", "BROKEN", "n/a (no front)"]
    us = slowest_front(2000.0, 1235.0, 1900.0, eos)
    assert us == pytest.approx(2000.0 / (1.0 - 1235.0 / fr.compacted_density(
        1235.0 * us * 2000.0, 1900.0, eos)), rel=1e-10)
    assert np.isnan(slowest_front(2000.0, 1235.0, 1900.0, lin))


def test_folded_area_of_a_corner_pushed_past_the_diagonal():
    """A unit square: nothing folded; corner 2 moved to (0.25, 0.25): the triangle of corners
    1, 2, 3, area 1/4."""
    from pdfem.mesh.quality import folded_area

    x = np.array([[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]])
    conn = np.array([[0, 1, 2, 3]])
    assert folded_area(x, conn)[0] == 0.0
    x[2] = [0.25, 0.25]
    assert folded_area(x, conn)[0] == pytest.approx(0.25, rel=1e-15)


def test_hugoniot_and_window_mean():
    """Bed strain from the faces, gauge means over frames, time-averaged window stress."""
    t = np.linspace(0.0, 1.0, 11)
    gt = np.linspace(0.0, 1.0, 1001)
    hug = fr.hugoniot(t, 2.0 - 0.5 * t, np.zeros(11), 2.0, gt, 3.0 * np.ones(1001), gt, 1000.0)
    assert hug["ev"][-1] == pytest.approx(0.25)
    assert hug["density"][-1] == pytest.approx(1000.0 / 0.75)
    assert hug["stress"][5] == pytest.approx(0.5 * (3.0 + 0.5))
    assert fr.window_mean(gt, gt, 0.2, 0.6) == pytest.approx(0.4)
    assert fr.first_rise(gt, np.where(gt > 0.3, 1.0, 0.0)) == pytest.approx(gt[gt > 0.3][0])
    assert np.isnan(fr.first_rise(gt, np.zeros_like(gt)))


def test_analyse_synthetic(tmp_path):
    """analyse(): known Us, up, rho1, sigma, closures, arrival; JSON, text and four PNGs."""
    path = make_run(str(tmp_path / "run.h5"))
    prefix = str(tmp_path / "out")
    s = analyse(path, prefix, extra={"wall": 1.5})
    assert s["bed"]["rho0"] == pytest.approx(RHO0, rel=1e-9)
    assert s["bed"]["H0"] == pytest.approx(H0) and s["bed"]["top_from"] == "hammer face"
    assert s["front"]["us"] == pytest.approx(US, rel=0.01)
    assert s["front"]["steadiness"] == "steady"
    assert s["shocked"]["up"] == pytest.approx(UP, rel=1e-6)
    assert s["shocked"]["rho1"] == pytest.approx(RHO1, rel=0.04)
    assert s["shocked"]["sigma"] == pytest.approx(SIGMA, rel=1e-9)
    assert s["shocked"]["sigma_source"] == "piston force"
    assert s["jump"]["mass_closure"] < 0.04 and s["jump"]["momentum_closure"] < 0.03
    assert s["jump"]["mass_strain_closure"] < 0.1
    assert s["drive"]["kind"] == "piston" and s["drive"]["face_deviation"] == 0.0
    assert s["front"]["arrival_fit"] == pytest.approx(T_ARR, rel=0.03)
    assert s["front"]["arrival_gauge"] == pytest.approx(T_ARR, rel=0.01)
    assert s["gauges"]["hammer_peak"] == pytest.approx(SIGMA)
    assert s["compaction"]["peak"] > 0.3 and s["snowplow"]["us"] < US
    assert s["bound"]["kept"] and s["mesh"]["folded_max"] == 0.0
    assert s["reference"]["us_min_at_impact_speed"] == pytest.approx(829.1, abs=1.0)
    assert s["reference"]["up_max_at_reference_us"] == pytest.approx(173.7, abs=0.5)
    assert s["run"] == {"wall": 1.5}
    assert s["energy"]["balance_error_last"] == pytest.approx(1e-3)
    js = json.loads((tmp_path / "out-summary.json").read_text())
    assert js["front"]["us"] == pytest.approx(s["front"]["us"]) and "arrays" not in js
    txt = (tmp_path / "out-summary.txt").read_text()
    assert "Us =" in txt and "1997" in txt
    for name in ("snapshots", "gauges", "xt", "hugoniot"):
        data = (tmp_path / f"out-{name}.png").read_bytes()
        assert data[:8] == b"\x89PNG\r\n\x1a\n" and len(data) > 1000
    assert not list(tmp_path.glob("*.part"))


def test_jump_figure_with_a_sweep(tmp_path):
    """The jump-state figure takes a sweep's steady states (a stopped row, with no front, is
    left out) and static curve."""
    path = make_run(str(tmp_path / "run.h5"))
    pts = [{"us": 2.5 * v, "rho1": 1700.0 + v, "sigma": 1240.0 * 1.5 * v * v}
           for v in (100.0, 288.0)] + [{"us": None, "rho1": None, "sigma": None}]
    static = {"density": list(np.linspace(1240.0, 1950.0, 20)),
              "sigma_piston": list(np.linspace(0.0, 5e8, 20))}
    analyse(path, str(tmp_path / "out"), sweep={"points": pts, "static": static})
    data = (tmp_path / "out-hugoniot.png").read_bytes()
    assert data[:8] == b"\x89PNG\r\n\x1a\n" and len(data) > 1000


def test_analyse_without_shock_table(tmp_path):
    """An older file without [shock]: InputError naming the file."""
    path = make_run(str(tmp_path / "old.h5"), shock=False, nframes=5)
    with pytest.raises(InputError, match="old.h5: no \\[shock\\] table"):
        analyse(path, str(tmp_path / "old"))


def test_sweep_plot(tmp_path):
    """The velocity-sweep figure is written, with an unsteady point, the crystal's Hugoniot
    and a static curve."""
    pts = [{"velocity": v, "us": 2.5 * v, "us_fit": 2.5 * v, "precursor": 2.7 * v,
            "up": 0.6 * v, "sigma": 1240.0 * 1.5 * v * v, "rho0": 1240.0, "rho1": 1700.0,
            "solid_density": 1900.0, "crystal_hugoniot": [2770.0, 2.29]}
           for v in (100.0, 288.0)]
    pts.append({"velocity": 400.0, "us": None, "us_fit": 900.0, "precursor": None,
                "up": 380.0, "sigma": None, "rho0": 1240.0, "rho1": None,
                "solid_density": 1900.0})
    static = {"density": np.linspace(1240.0, 1950.0, 20),
              "sigma_piston": np.linspace(0.0, 5e8, 20), "sigma_anvil": np.linspace(0, 5e8, 20),
              "floor": 5e6}
    sweep_plot(pts, str(tmp_path / "sweep.png"), static=static)
    assert (tmp_path / "sweep.png").read_bytes()[:4] == b"\x89PNG"


def test_analyse_temperature_without_velocities(tmp_path):
    """Temperature adds a snapshot row; missing velocities are differenced from positions."""
    path = make_run(str(tmp_path / "heat.h5"))
    with h5py.File(path, "a") as f:
        f["frames/temperature"] = 300.0 + np.zeros(f["frames/x"].shape[:2])
        del f["frames/v"]
    s = analyse(path, str(tmp_path / "heat"))
    assert s["front"]["us"] == pytest.approx(US, rel=0.02)
    assert s["shocked"]["up"] == pytest.approx(UP, rel=0.02)
    assert any("differenced" in n for n in s["notes"])
    assert (tmp_path / "heat-snapshots.png").stat().st_size > 1000


def test_nodes_inside_another_grains_interior_elements():
    """A 3 x 3 grain has one interior element (the centre); a node of another grain inside it
    is counted, one inside a boundary element (ordinary contact overlap) or on no element is
    not, and the grain's own nodes never are."""
    from pdfem.tools.analysis.interpenetration import interior_elements, nodes_inside_interiors

    # Grain 0: unit quads on [0, 3]^2, nodes i + 4 j, counter-clockwise
    xa = np.array([[i, j] for j in range(4) for i in range(4)], float)
    conn = np.array([[i + 4 * j, i + 1 + 4 * j, i + 5 + 4 * j, i + 4 + 4 * j]
                     for j in range(3) for i in range(3)])
    assert np.flatnonzero(interior_elements(conn)).tolist() == [4]
    # Grain 1: one quad whose corners sit in the centre element, a boundary element, outside
    xb = np.array([[1.5, 1.5], [2.5, 0.5], [4.0, 0.5], [4.0, 1.5]])
    x = np.vstack([xa, xb])
    conn_all = np.vstack([conn, [[16, 17, 18, 19]]])
    node_body = np.array([0] * 16 + [1] * 4)
    elem_body = np.array([0] * 9 + [1])
    inside = nodes_inside_interiors(x, conn_all, elem_body, node_body)
    assert np.flatnonzero(inside).tolist() == [16]
    # Moved out of the centre element, nothing is inside
    x[16] = [0.5, 2.5]
    assert not nodes_inside_interiors(x, conn_all, elem_body, node_body).any()


def test_escape_depths_beyond_the_anvil_the_hammer_and_the_sides():
    """The farthest excursion of the grain nodes past each confine, over the frames, and the
    frame where it is; negative when a grain never got there; the reach of a scene's contact
    is the largest delta_max of its table and pairs."""
    from pdfem.tools.analysis.escape import contact_reach, escape_depths, escaped_mass

    box = [0.0, 0.0, 1.0, 4.0]
    bottom = np.array([1.5, 0.9, 0.7])
    top = np.array([3.0, 3.2, 2.9])
    xr = np.array([[0.1, 0.9], [-0.05, 0.95], [0.0, 1.2]])
    anvil = np.array([1.0, 1.0, 0.95])
    hammer = np.array([3.5, 3.1, 2.8])
    e = escape_depths(bottom, top, xr, anvil, hammer, box)
    assert e["below_anvil"] == pytest.approx(0.25) and e["below_anvil_frame"] == 2
    assert e["above_hammer"] == pytest.approx(0.1) and e["above_hammer_frame"] == 1
    assert e["past_sides"] == pytest.approx(0.2) and e["past_sides_frame"] == 2
    e = escape_depths(bottom[:1], top[:1], xr[:1], anvil[:1], hammer[:1], box)
    assert e["below_anvil"] == pytest.approx(-0.5) and e["above_hammer"] == pytest.approx(-0.5)
    assert e["past_sides"] == pytest.approx(-0.1)
    assert contact_reach({}) == 0.0
    # Two unit quads of masses 1 and 3; a node of the second past the anvil's face: 3/4
    y = np.array([0.0, 0.0, 1.0, 1.0, 0.0, 0.0, 1.0, 1.0])
    gconn = np.array([[0, 1, 2, 3], [4, 5, 6, 7]])
    y[5] = -0.5
    assert escaped_mass(y, gconn, np.array([1.0, 3.0]), -0.1, 2.0) == 0.75
    assert escaped_mass(y, gconn, np.array([1.0, 3.0]), -0.6, 2.0) == 0.0
    assert escaped_mass(y, gconn, np.array([1.0, 3.0]), -0.6, 0.9) == 1.0
    assert contact_reach({"contact": {"delta_max": 3e-5, "pairs": {"a:b": {"delta_max": 5e-5},
                                                                  "a:c": {"kn0": 1.0}}}}) == 5e-5


def test_snapshots_fold_a_periodic_mesh_into_the_box():
    # An element that drifted a box width and a half out through the right side is drawn at
    # its image inside the box, and once more a width to either side (cut by the panel)
    import matplotlib.pyplot as plt

    from pdfem.tools.analysis.plots import _mesh_panel

    x = np.array([[2.4, 0.1], [2.6, 0.1], [2.6, 0.3], [2.4, 0.3]]) * 1e-3
    conn = np.array([[0, 1, 2, 3]])
    fig, ax = plt.subplots()
    pc = _mesh_panel(ax, x, conn, np.ones(1), None, "inferno", (0.0, 0.0, 1.0e-3, 1.0e-3), True)
    centres = sorted(p.vertices[:4, 0].mean() for p in pc.get_paths())
    plt.close(fig)
    assert np.allclose(centres, [-0.5, 0.5, 1.5])


def test_escape_line_says_whether_the_material_came_back():
    """The summary's escape line calls grain material past the anvil lost only while some of it
    is still past at the end; a corner pressed in and out again is said to be back."""
    from pdfem.tools.analysis.report import _escape_line

    e = {"below_anvil": 42e-6, "above_hammer": 1e-6, "reach": 30e-6, "past_sides": None,
         "escaped": True, "mass": 4.7e-4, "t_mass": 0.44e-6, "mass_end": 0.0}
    line = _escape_line(e)
    assert "periodic sides" in line and "all back by the end" in line
    assert "lost" not in line
    line = _escape_line(dict(e, mass_end=1e-4, past_sides=2e-6))
    assert line.endswith("lost to the bed") and "2.0 um past the box's sides" in line
    assert "gone past" not in _escape_line(dict(e, escaped=False))
