"""Heat: conduction, dissipation heating, thermo-elastic coupling, energy, effects off."""

import h5py
import numpy as np
import pytest
from mpi4py import MPI

from pdfem.driver import run
from pdfem.effects import REGISTRY
from pdfem.energy import ROLES
from pdfem.errors import InputError, SimulationError
from pdfem.io.contacts import contact_rows, split_rows
from pdfem.kernels.element_measures import q4_lumped_mass
from pdfem.kernels.heat import conduction_flows, element_to_nodes
from pdfem.kernels.params import COND, NPAR, RHO
from pdfem.scene import parse_scene
from pdfem.solver import Simulation
from tests.scenes import collision


def sand():
    """A cap sand with thermal properties."""
    return {"model": "cap", "density": 1700.0, "bulk": 459673449.19, "shear": 275790280.0,
            "A": 1723689.25, "B": 9.717528841117968e-08, "C": 1241056.26,
            "D": 9.717528841117968e-08, "R": 2.5, "W": 0.066, "kappa0": 0.0,
            "specific_heat": 800.0, "conductivity": 0.3, "expansion": 1.0e-5}


def plain_m(**thermal):
    """An elastic material without thermal properties (``thermal``: keys to add)."""
    return {"density": 1900.0, "bulk": 12.7e9, "shear": 4.4e9, **thermal}


def block_scene(material, box, nx, ny, end, extra=None, out="run.h5"):
    """One block body of the material dict ``material`` (named m), with the tables of
    ``extra`` (a dict) added."""
    doc = {
        "domain": {"box": list(box)},
        "time": {"end": end, "safety": 0.5},
        "output": {"path": out, "interval": end / 4, "energy_interval": end / 40},
        "materials": {"m": material},
        "blocks": [{"name": "b", "box": list(box), "nx": nx, "ny": ny, "material": "m"}],
    }
    for key, value in (extra or {}).items():
        assert key not in doc, key
        doc[key] = value
    return doc


def _bc(nodes, kind, **more):
    """A boundary condition on the nodes ``nodes`` of block b."""
    return {"body": "b", "nodes": nodes, "type": kind, **more}


def simulate(doc, tmp_path):
    return Simulation(parse_scene(doc, str(tmp_path)), MPI.COMM_SELF)


# ---- kernels -------------------------------------------------------------------------------

def test_conduction_flows_patch_and_balance():
    """A linear temperature field drives no flow at interior nodes; flows sum to zero."""
    rng = np.random.default_rng(4)
    gx, gy = np.meshgrid(np.arange(4.0), np.arange(4.0), indexing="xy")
    x = np.stack([gx.ravel(), gy.ravel()], axis=1)
    x[[5, 6, 9, 10]] += rng.uniform(-0.2, 0.2, (4, 2))
    n0 = (np.arange(3)[None, :] + 4 * np.arange(3)[:, None]).ravel()
    conn = np.stack([n0, n0 + 1, n0 + 5, n0 + 4], axis=1).astype(np.int64)
    mat = np.zeros((1, NPAR))
    mat[0, COND] = 2.5
    emat = np.zeros(9, np.int32)
    temp = 3.0 * x[:, 0] - 2.0 * x[:, 1] + 7.0
    q = np.zeros(16)
    assert conduction_flows(x, temp, conn, emat, mat, 0, 9, q) == -1
    assert np.abs(q[[5, 6, 9, 10]]).max() < 1e-12
    assert abs(q.sum()) < 1e-12
    # A boundary node's flow is the flux k grad T . n times its share of the boundary
    assert q[:4].sum() == pytest.approx(-2.5 * 2.0 * 3.0, rel=1e-12)
    # element_to_nodes conserves each element's value
    out = np.zeros(16)
    element_to_nodes(x, conn, 0, 9, np.arange(1.0, 10.0), out)
    assert out.sum() == pytest.approx(45.0, rel=1e-14)
    # The lumped capacity of a parallelogram is a quarter of rho c A per node
    m = np.zeros(16)
    mat[0, RHO] = 2.0
    q4_lumped_mass(x, conn, emat, mat, 0, 1, m)
    d1, d2 = x[5] - x[0], x[4] - x[1]
    assert m[[0, 1, 5, 4]].sum() == pytest.approx(0.5 * 2.0 * abs(d1[0] * d2[1] - d1[1] * d2[0]),
                                                  rel=1e-12)


# ---- closed forms through the solver --------------------------------------------------------

def test_conduction_along_a_bar_matches_the_analytic_decay(tmp_path):
    """T = T0 + dT cos(pi x / L) on an insulated bar decays as exp(-kappa pi^2 t / L^2)."""
    length, rho, c, k = 0.01, 1000.0, 1000.0, 1.0e4
    kappa = k / (rho * c)
    tau = length**2 / (kappa * np.pi**2)
    mat = {"density": rho, "bulk": 1.0e6, "shear": 6.0e5, "specific_heat": c,
           "conductivity": k}
    doc = block_scene(mat, (0.0, 0.0, length, 0.001), 40, 4, 0.5 * tau,
                       extra={"heat": {"initial": 300.0}, "conduction": {}})
    sim = simulate(doc, tmp_path)
    s = sim.store
    s.T[:] = 300.0 + 10.0 * np.cos(np.pi * s.x[:, 0] / length)
    while sim.t < sim.t_end:
        sim.step()
    assert sim.heat.nsub > 1  # the conduction limit is the tighter one here: sub-cycled
    exact = 300.0 + 10.0 * np.cos(np.pi * s.x[:, 0] / length) * np.exp(-sim.t / tau)
    assert np.abs(s.T - exact).max() < 0.01 * 10.0 * np.exp(-sim.t / tau)
    assert sim.timers.calls["heat"] > 0


def compressed_sand(tmp_path, extra, end=2.0e-5, v=-1.0):
    """A sand block in uniaxial strain: fixed bottom, rollers at the sides, top pushed down;
    ``extra``: more tables (a dict)."""
    bcs = [_bc("bottom", "fixed"), _bc("left", "roller"), _bc("right", "roller"),
           _bc("top", "velocity", dof="y", velocity=[0.0, v])]
    doc = block_scene(sand(), (0.0, 0.0, 0.001, 0.001), 4, 4, end, extra={"bc": bcs, **extra})
    return simulate(doc, tmp_path)


def test_adiabatic_block_heats_by_beta_wp_over_rho_c(tmp_path):
    sim = compressed_sand(tmp_path, {"heat": {"initial": 300.0},
                                     "dissipation_heating": {"beta": 0.8}})
    while sim.t < sim.t_end:
        sim.step()
    s = sim.store
    wp = s.ewp.sum()
    assert wp > 0.0
    # Mean temperature rise (capacity-weighted) against beta W_p / (rho c V)
    rise = (s.tcap * (s.T - 300.0)).sum() / s.tcap.sum()
    assert rise == pytest.approx(0.8 * wp / (1700.0 * 800.0 * 1e-6), rel=0.01)
    # Element by element: each element's heat lands on its nodes (no conduction)
    assert (s.T - 300.0).min() >= 0.0


def test_adiabatic_elastic_compression_heats_by_3_alpha_t0_p_over_rho_c(tmp_path):
    """Kelvin's thermo-elastic effect: an elastic block compressed in uniaxial strain,
    without conduction, heats by dT = 3 alpha T0 p / (rho c) (p its pressure), and the
    balance, which pays that heat from the coupling energy -3 alpha T p A, closes."""
    rho, c, alpha, t0 = 1900.0, 1000.0, 5.0e-5, 300.0
    mat = plain_m(specific_heat=c, expansion=alpha)
    mat["density"] = rho
    bcs = [_bc("left", "roller"), _bc("right", "roller"), _bc("bottom", "fixed"),
           _bc("top", "velocity", dof="y", velocity=[0.0, -0.05])]
    extra = {"heat": {"initial": t0}, "thermoelastic": {}, "thermal_expansion": {}, "bc": bcs}
    doc = block_scene(mat, (0.0, 0.0, 0.001, 0.001), 4, 4, 2.0e-5, extra=extra)
    sim = simulate(doc, tmp_path)
    summary = run(sim, str(tmp_path / "te.h5"), quiet=True)
    s = sim.store
    p = -(s.sig[:, :, 0] + s.sig[:, :, 1] + s.sig[:, :, 3]).mean(axis=1) / 3.0
    rise = (s.tcap * (s.T - t0)).sum() / s.tcap.sum()
    assert p.mean() > 1.0e7 and rise > 0.0
    assert rise == pytest.approx(3.0 * alpha * t0 * p.mean() / (rho * c), rel=0.01)
    with h5py.File(tmp_path / "te.h5") as f:
        coupling, thermal = f["energy/coupling"][()], f["energy/thermal"][()]
    # The coupling energy paid for the heat (its fall equals the heat, to first order)
    assert coupling[-1] < 0.0 and -coupling[-1] == pytest.approx(thermal[-1], rel=0.05)
    assert summary["balance_error"] < 1.0e-3, summary["balance_error"]


def test_a_heat_source_that_no_mechanics_pays_for_trips_the_energy_guard(tmp_path):
    """A spurious source (here: the dissipation heating counted twice, through a test-only
    wrapper of the heat update, booked like every source) is seen by the balance: the drift
    guard stops the run. The same run without it closes within 1 %."""
    extra = {"heat": {"initial": 300.0}, "dissipation_heating": {"beta": 0.8}}
    sim = compressed_sand(tmp_path, extra, end=4.0e-5)
    summary = run(sim, str(tmp_path / "good.h5"), quiet=True)
    assert summary["balance_error"] < 0.01

    sim = compressed_sand(tmp_path, {"guards": {"energy_drift": 0.05}, **extra}, end=4.0e-5)
    heat = sim.heat
    plain = type(heat).heat
    last = sim.store.ewp.copy()

    def heat_twice(self, st, ctx):
        # beta x the step's plastic work once more, on the element's nodes and in the books
        s = st.store
        extra_heat = 0.8 * (s.ewp - last)
        last[:] = s.ewp
        element_to_nodes(s.x, s.conn, 0, s.ne_own, extra_heat, self.src)
        plain(self, st, ctx)

    heat.heat = heat_twice.__get__(heat)
    with pytest.raises(SimulationError, match="check energy drift"):
        run(sim, str(tmp_path / "bad.h5"), quiet=True)


def test_thermoelastic_block_expands_by_the_thermal_strain(tmp_path):
    """A free elastic block held at T0 + 100 K expands in plane strain by (1 + nu) alpha dT."""
    kb, gs, alpha = 12.7e9, 4.4e9, 1.0e-4
    nu = (3 * kb - 2 * gs) / (2 * (3 * kb + gs))
    mat = {"density": 1900.0, "bulk": kb, "shear": gs, "specific_heat": 1000.0,
           "expansion": alpha}
    heat = {"heat": {"initial": 300.0}, "thermal_expansion": {}, "thermoelastic": {},
            "damping": {"gamma": 4.0e6}, "thermal_bc": [{"body": "b", "temperature": 400.0}]}
    doc = block_scene(mat, (0.0, 0.0, 0.001, 0.001), 4, 4, 6.0e-6, extra=heat)
    sim = simulate(doc, tmp_path)
    s = sim.store
    w0 = s.x[:, 0].max() - s.x[:, 0].min()
    while sim.t < sim.t_end:
        sim.step()
    s = sim.store
    strain = (s.x[:, 0].max() - s.x[:, 0].min()) / w0 - 1.0
    assert strain == pytest.approx((1 + nu) * alpha * 100.0, rel=0.01)
    assert np.all(s.T == 400.0)


def test_without_heat_no_temperature_exists(tmp_path):
    doc = block_scene(plain_m(), (0.0, 0.0, 0.001, 0.001), 2, 2, 1e-7, out="cold.h5")
    sim = simulate(doc, tmp_path)
    assert not hasattr(sim.store, "T") and sim.heat is None
    assert sim.effect_names == []
    run(sim, str(tmp_path / "cold.h5"), quiet=True)
    assert sim.timers.calls["heat"] == 0 and sim.timers.seconds["heat"] == 0.0
    with h5py.File(tmp_path / "cold.h5") as f:
        assert "temperature" not in f["frames"]
        assert f.attrs["effects"] == ""


def test_energy_balance_closes_with_heat_on(tmp_path):
    """Plastic heating, conduction, thermo-elastic coupling and thermal expansion together."""
    sim = compressed_sand(tmp_path, {"heat": {"initial": 300.0}, "conduction": {},
                                     "dissipation_heating": {}, "thermoelastic": {},
                                     "thermal_expansion": {}}, end=4.0e-5)
    out = tmp_path / "hot.h5"
    summary = run(sim, str(out), quiet=True)
    with h5py.File(out) as f:
        err = f["energy/balance_error"][()]
        thermal = f["energy/thermal"][()]
        plastic = f["energy/plastic"][()]
        assert f["frames/temperature"].shape[1] == sim.layout.nnode
        assert f.attrs["effects"] == ("cap_plasticity,heat,conduction,dissipation_heating,"
                                      "thermoelastic,thermal_expansion")
    assert thermal[-1] > 0.5 * plastic[-1] > 0.0
    assert err.max() < 0.01, err.max()
    assert summary["balance_error"] < 0.01
    # The error recomputed from the stored terms: E from the balance's terms, with their signs
    with h5py.File(out) as f:
        terms = {t: f[f"energy/{t}"][()] for t in f["energy"]
                 if t not in ("time", "total", "balance_error")}
        total = f["energy/total"][()]
    assert {"thermal", "heat_paid", "coupling", "heat_sources"} <= set(terms)
    parts = [t for t in terms if ROLES[t] != 0]
    e = sum(ROLES[t] * terms[t] for t in parts)
    assert np.allclose(e, total, rtol=1e-12, atol=1e-12 * np.abs(total).max())
    scale = np.array([max(abs(terms[t][k] - (terms[t][0] if t == "potential" else 0.0))
                          for t in parts for k in (0, i)) for i in range(e.shape[0])])
    assert np.allclose(np.abs(e - e[0]) / np.maximum(scale, 1e-300), err, rtol=1e-6,
                       atol=1e-12)
    # Every source is paid: the heat in the block is beta W_p plus the thermo-elastic heat,
    # which the coupling energy lost
    assert terms["heat_paid"][-1] == pytest.approx(0.9 * plastic[-1], rel=1e-9)


def _oblique_and_thermal(doc):
    """The collision scene ``doc`` changed: the left grain also moves up at 8 m/s, and the
    grain material conducts heat."""
    assert doc["grains"][0]["velocity"] == [20.0, 0.0]
    doc["grains"][0]["velocity"] = [20.0, 8.0]
    doc["materials"]["grain"].update(specific_heat=1000.0, conductivity=0.4)


def test_contact_heat_balance_and_friction(tmp_path):
    """Two grains collide obliquely with friction: friction heats both, energy closes."""
    doc = collision(v=20.0, mu=0.5, end=6e-6, extra={
        "heat": {"initial": 300.0}, "conduction": {}, "contact_conductance": {"h": 1.0e7},
        "friction_heating": {}})
    _oblique_and_thermal(doc)
    sim = simulate(doc, tmp_path)
    out = tmp_path / "c.h5"
    run(sim, str(out), quiet=True)
    with h5py.File(out) as f:
        err = f["energy/balance_error"][()]
        fric = f["energy/friction"][()]
        thermal = f["energy/thermal"][()]
    assert fric[-1] > 0.0
    assert thermal[-1] == pytest.approx(fric[-1], rel=1e-6)
    # The oblique overlap contact itself closes its balance to about 1 % (dt -> 0: 1.1 %)
    assert err.max() < 0.02


def test_per_contact_heat_is_h_width_delta_t(tmp_path):
    """The per-contact output's heat: with each grain at a uniform temperature, a contact
    passes h w (T_B - T_A) from B into A (w its width), whatever the friction does."""
    h = 1.0e7
    doc = collision(v=20.0, mu=0.5, end=6e-6, extra={
        "heat": {"initial": 300.0}, "contact_conductance": {"h": h}, "friction_heating": {}})
    _oblique_and_thermal(doc)
    sim = simulate(doc, tmp_path)
    checked = 0
    while sim.t < sim.t_end and checked < 20:
        s = sim.store
        temp = {0: 300.0, 1: 450.0}
        s.T[:] = [temp[int(g)] for g in s.gid[s.node_body]]
        sim.step()
        rows = split_rows(contact_rows(sim.state, sim.ctx))
        for key, w, q in zip(rows["key"], rows["width"], rows["heat"], strict=True):
            assert q == pytest.approx(h * w * (temp[int(key[2])] - temp[int(key[0])]),
                                      rel=1e-12)
            checked += 1
    assert checked >= 20


@pytest.mark.parametrize("name", [n for n in REGISTRY if n not in
                                  ("gravity", "damping", "bulk_viscosity", "contact", "heat",
                                   "cap_plasticity", "contact_friction")])
def test_heat_effect_without_heat_table_is_an_error(tmp_path, name):
    mat = plain_m(specific_heat=1.0, conductivity=1.0, expansion=1e-5, softening=1e-3)
    body = {"contact_conductance": {"h": 1.0}}.get(name, {})
    doc = block_scene(mat, (0.0, 0.0, 0.001, 0.001), 2, 2, 1e-7, extra={name: body})
    with pytest.raises(InputError, match=f"{name}: needs the \\[heat\\] table"):
        parse_scene(doc, str(tmp_path))


@pytest.mark.parametrize("one,other", [("thermoelastic", "thermal_expansion"),
                                       ("thermal_expansion", "thermoelastic")])
def test_thermoelastic_heating_and_thermal_expansion_come_together(tmp_path, one, other):
    """Either half of the thermo-elastic coupling alone creates energy: refused, naming the
    missing table."""
    mat = plain_m(specific_heat=1000.0, expansion=1e-5)
    doc = block_scene(mat, (0.0, 0.0, 0.001, 0.001), 2, 2, 1e-7,
                       extra={"heat": {"initial": 300.0}, one: {}})
    with pytest.raises(InputError, match=f": {one}: needs the \\[{other}\\] table: "
                       "thermo-elastic heating and thermal expansion are one coupling"):
        parse_scene(doc, str(tmp_path))


def test_missing_material_input_names_the_key(tmp_path):
    doc = block_scene(plain_m(), (0.0, 0.0, 0.001, 0.001), 2, 2, 1e-7, extra={"heat": {}})
    with pytest.raises(InputError, match=r"materials\.m\.specific_heat: required by \[heat\]"):
        parse_scene(doc, str(tmp_path))
    doc = block_scene(plain_m(specific_heat=1.0), (0.0, 0.0, 0.001, 0.001), 2, 2, 1e-7,
                       extra={"heat": {}, "conduction": {}})
    with pytest.raises(InputError, match=r"materials\.m\.conductivity: required by "
                                         r"\[conduction\]"):
        parse_scene(doc, str(tmp_path))


def test_temperature_dependence_softens_the_elastic_increment():
    """With softening s, a patch strained at T = T_ref + 100 gets K, G x (1 - 100 s)."""
    from pdfem.kernels.element_1pt import q4_forces_1pt
    from pdfem.kernels.material import SOFT_FLOOR, softened
    from pdfem.kernels.params import BULK, MODEL, SHEAR, SOFT_K, T_REF

    p = np.zeros(NPAR)
    p[[RHO, BULK, SHEAR, SOFT_K, T_REF]] = [1900.0, 10e9, 4e9, 2e-3, 300.0]
    out = np.empty(NPAR)
    softened(p, 400.0, out)
    assert out[BULK] == pytest.approx(8e9, rel=1e-14) and out[SHEAR] == pytest.approx(3.2e9)
    softened(p, 1000.0, out)
    assert out[BULK] == pytest.approx(SOFT_FLOOR * 10e9)
    # One element, uniform strain increment at 400 K: sigma = C(T) : deps
    x = np.array([[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]])
    conn = np.array([[0, 1, 2, 3]], np.int64)
    du = 1e-6 * x[:, 0:1] * np.array([[1.0, 0.0]])
    mat = p[None, :].copy()
    mat[0, MODEL] = 0.0
    sig = np.zeros((1, 1, 4))
    eth = np.array([[0.0, 400.0, 0.0]])
    q4_forces_1pt(x + du, du, conn, np.zeros(1, np.int32), mat, sig, np.zeros((1, 1, 0)),
                  np.zeros((0, 6)), 0, 0, 1, np.zeros((4, 2)), np.zeros(1), np.zeros(1), eth)
    kb, g = 8e9, 3.2e9
    # (the mid-step gradient du / (x - du/2) differs from 1e-6 by 5e-7 relative)
    assert sig[0, 0, 0] == pytest.approx((kb + 4 * g / 3) * 1e-6, rel=1e-5)
    assert sig[0, 0, 1] == pytest.approx((kb - 2 * g / 3) * 1e-6, rel=1e-5)
