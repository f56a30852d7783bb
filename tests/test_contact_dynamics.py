"""Contact through the whole solver: collision, rest, incline, and no missed contact."""

import numpy as np
import pytest
from mpi4py import MPI

from pdfem.energy import global_terms
from pdfem.io.contacts import contact_rows, split_rows
from pdfem.kernels import contact_law as L
from pdfem.kernels.broad_phase import element_bboxes, pairs_from_bboxes
from pdfem.kernels.contact import C_ACTIVE, NRES, element_pair_forces, element_wall_forces
from pdfem.scene import parse_scene
from pdfem.solver import Simulation
from tests.scenes import collision, elastic, settling_bed


def _contact(sim):
    return [e for e in sim.effects if e.name == "contact"][0]


def _com_velocity(sim, gid):
    s = sim.store
    b = int(np.nonzero(s.gid == gid)[0][0])
    i = slice(s.nstart[b], s.nstart[b] + s.nn[b])
    return (s.m[i, None] * s.v[i]).sum(0) / s.m[i].sum()


def test_head_on_collision_exchanges_velocities(tmp_path):
    v0 = 20.0
    sim = Simulation(parse_scene(collision(v=v0, kn0=1e13, end=2e-5), str(tmp_path)),
                     MPI.COMM_SELF)
    s = sim.store
    scale = s.m.sum() * v0
    k0 = global_terms(sim.state, sim.ctx)["kinetic"]
    touched = False
    while sim.t < sim.t_end:
        sim.step()
        s = sim.store
        # Momentum to round-off at every step
        assert np.abs((s.m[:, None] * s.v).sum(0)).max() <= 1e-12 * scale
        n = int((_contact(sim).last["active"] == C_ACTIVE).sum())
        touched |= n > 0
        if touched and n == 0:
            break
    assert touched and sim.t < sim.t_end
    va, vb = _com_velocity(sim, 0), _com_velocity(sim, 1)
    assert va[0] == pytest.approx(-v0, rel=0.02) and vb[0] == pytest.approx(v0, rel=0.02)
    m = sim.store.m.sum() / 2
    assert 0.5 * m * (va @ va + vb @ vb) == pytest.approx(k0, rel=0.02)


def _collide(tmp_path, damping, v0=20.0):
    """Run the head-on collision until the grains part; (rebound speed / v0, energy balance
    error, contact_damping / initial kinetic energy, contact_loss / initial kinetic energy)."""
    from pdfem.energy import balance

    sim = Simulation(parse_scene(collision(v=v0, kn0=1e13, end=2e-5, damping=damping),
                                 str(tmp_path)), MPI.COMM_SELF)
    ref = global_terms(sim.state, sim.ctx)
    touched = False
    while sim.t < sim.t_end:
        sim.step()
        n = int((_contact(sim).last["active"] == C_ACTIVE).sum())
        touched |= n > 0
        if touched and n == 0:
            break
    terms = global_terms(sim.state, sim.ctx)
    return (-_com_velocity(sim, 0)[0] / v0, balance(terms, ref)[1],
            terms["contact_damping"] / ref["kinetic"], terms["contact_loss"] / ref["kinetic"])


def test_contact_damping_takes_energy_out_and_the_balance_closes(tmp_path):
    e0, err0, damp0, loss0 = _collide(tmp_path, 0.0)
    e1, err1, damp1, loss1 = _collide(tmp_path, 0.5)
    e2, err2, damp2, loss2 = _collide(tmp_path, 1.0)
    # Undamped: elastic rebound, nothing damped, the contacts conserve energy (measured:
    # rebound 0.997, contact_loss 0)
    assert e0 == pytest.approx(1.0, abs=0.01) and damp0 == 0.0 and abs(loss0) < 5e-4
    # Damped: a slower rebound (0.952, 0.912); the damping's dissipation is what the grains lost
    # and the balance, which includes whatever the contacts do, closes (measured: contact_loss
    # 3e-5 and 9e-5 of the impact energy, balance errors 2e-5 to 7e-5)
    assert e2 < e1 < 0.97 * e0
    assert damp1 > 0.05 and damp2 > damp1
    assert max(abs(loss1), abs(loss2)) < 5e-4
    assert max(err0, err1, err2) < 5e-4


def test_damped_traction_and_its_time_step():
    # A flat contact of width gn = L = 0.5: the spring in the gap h is kt gn^2 / L, its critical
    # damping 2 sqrt(m k); on the area (dA = gn dh) that is c_A = c / gn^2
    kt, m, length, gn, zeta = 5.0, 2.0, 0.5, 0.5, 0.3
    c = 2 * zeta * np.sqrt(m * kt * gn**2 / length)
    # Closing at 2 m/s (area growing at gn x 2) adds c x 2 / gn to the traction
    assert L.damped_traction(1.0, kt, 2.0 * gn, m, length, gn, zeta) == pytest.approx(
        1.0 + c * 2.0 / gn)
    # Separating: less compression, never tension
    assert L.damped_traction(1.0, kt, -0.1 * gn, m, length, gn, zeta) == pytest.approx(
        1.0 - c * 0.1 / gn)
    assert L.damped_traction(1.0, kt, -10.0 * gn, m, length, gn, zeta) == 0.0
    assert L.damped_traction(1.0, kt, 2.0, m, length, gn, 0.0) == 1.0
    # The dashpot shortens the stable step by sqrt(1 + zeta^2) - zeta
    r = L.contact_dt(2.0, np.inf, 8.0, 0.5) / L.contact_dt(2.0, np.inf, 8.0)
    assert r == pytest.approx(np.sqrt(1.25) - 0.5, rel=1e-14)


def _rest():
    """One grain dropped onto a frictionless floor, damped."""
    return {
        "domain": {"box": [0.0, 0.0, 0.002, 0.002]},
        "time": {"end": 1.0e-4, "safety": 0.5},
        "element": {"level": 2},
        "gravity": {"g": [0.0, -1.0e4]},
        "damping": {"gamma": 3.0e5},
        "contact": {"kn0": 1.0e13, "delta_max": 2.0e-5},
        "walls": {"bottom": "frictionless"},
        "output": {"path": "rest.h5", "interval": 1.0e-4},
        "materials": {"grain": elastic()},
        "grains": [{"center": [0.001, 0.0002], "axes": [2.5e-4, 2.0e-4], "angle": 0.0,
                    "material": "grain"}],
    }


def test_grain_at_rest_on_the_floor_carries_its_weight(tmp_path):
    sim = Simulation(parse_scene(_rest(), str(tmp_path)), MPI.COMM_SELF)
    weight = sim.store.m.sum() * 1.0e4
    pe0 = global_terms(sim.state, sim.ctx)["potential"]
    # At rest: kinetic energy below 1e-6 of the potential energy drop for 10 samples running
    calm = 0
    while calm < 10 and sim.nstep < 100000:
        sim.step()
        if sim.nstep % 100 == 0:
            terms = global_terms(sim.state, sim.ctx)
            calm = calm + 1 if abs(terms["kinetic"]) < 1e-6 * (pe0 - terms["potential"]) else 0
    assert calm == 10
    last = _contact(sim).last
    on = last["active"] == C_ACTIVE
    assert on.any()
    assert last["fnod"][on, :4, 1].sum() == pytest.approx(weight, rel=0.005)


def _incline(theta, mu, g=1.0e4, end=4.0e-4):
    """A block on a frictional floor (friction mu), gravity tilted by theta."""
    gx, gy = float(g * np.sin(theta)), float(-g * np.cos(theta))
    return {
        "domain": {"box": [0.0, 0.0, 0.01, 0.002]},
        "time": {"end": end, "safety": 0.5},
        "gravity": {"g": [gx, gy]},
        "contact": {"kn0": 1.0e13, "delta_max": 2.0e-5},
        "walls": {"bottom": "frictional", "friction": mu},
        "output": {"path": "incline.h5", "interval": end},
        "materials": {"grain": elastic()},
        "blocks": [{"name": "block", "box": [0.001, 0.0, 0.002, 0.00025], "nx": 4, "ny": 1,
                    "material": "grain"}],
    }


def _block_velocity_history(sim):
    ts, vs = [], []
    while sim.t < sim.t_end:
        sim.step()
        s = sim.store
        ts.append(sim.t)
        vs.append((s.m * s.v[:, 0]).sum() / s.m.sum())
    return np.array(ts), np.array(vs)


def test_block_slides_down_incline_at_g_sin_minus_mu_cos(tmp_path):
    theta, mu, g = np.radians(30.0), 0.2, 1.0e4
    sim = Simulation(parse_scene(_incline(theta, mu, g), str(tmp_path)), MPI.COMM_SELF)
    t, v = _block_velocity_history(sim)
    late = t > 0.25 * t[-1]
    accel = np.polyfit(t[late], v[late], 1)[0]
    assert accel == pytest.approx(g * (np.sin(theta) - mu * np.cos(theta)), rel=0.02)


def test_block_sticks_when_tan_theta_below_mu(tmp_path):
    theta, mu, g = np.radians(10.0), 0.3, 1.0e4
    sim = Simulation(parse_scene(_incline(theta, mu, g), str(tmp_path)), MPI.COMM_SELF)
    t, v = _block_velocity_history(sim)
    free = g * np.sin(theta) * t[-1]
    assert np.abs(v[t > 0.25 * t[-1]]).max() < 0.01 * free


def test_no_contact_missed_on_a_dense_bed(tmp_path):
    # Let a bed fall and pack, then compare the contacts found with an all-pairs search
    sim = Simulation(parse_scene(settling_bed(n=120, cols=12), str(tmp_path)), MPI.COMM_SELF)
    for _ in range(12000):
        sim.step()
    s, eff = sim.store, _contact(sim)
    found = {tuple(k) for k, a in zip(eff.last["keys"], eff.last["active"], strict=True)
             if a == C_ACTIVE and k[2] >= 0}
    assert len(found) > 60
    bbox = np.empty((s.nelem, 4))
    element_bboxes(s.x, s.conn, 0, s.nelem, bbox)
    out = np.zeros((200000, 2), np.int64)
    n = pairs_from_bboxes(bbox, s.ebnd, s.elem_gid, s.elem_loc, 0, s.nelem, 0.0, out)
    pairs = out[:n]
    m = pairs.shape[0]
    act = np.empty(m, np.int8)
    res = np.empty((m, NRES))
    element_pair_forces(s.x, sim.du, s.conn, s.ebnd, s.elem_gid, s.elem_loc, s.elen, pairs,
                        np.tile([1e13, 2e-5, 5e12, 0.3, 0.95, 0.0], (m, 1)), np.zeros(m), act,
                        np.empty((m, 8), np.int64), np.empty((m, 8)), np.empty((m, 8, 2)),
                        np.empty(m), res, s.m, 0.0)
    brute = {(s.elem_gid[a], s.elem_loc[a], s.elem_gid[b], s.elem_loc[b])
             for (a, b), x in zip(pairs, act, strict=True) if x == C_ACTIVE}
    assert found == brute
    # Walls too: every boundary element against the floor
    cand = np.nonzero(s.ebnd.any(axis=1))[0]
    nw = cand.shape[0]
    wact = np.empty(nw, np.int8)
    element_wall_forces(s.x, sim.du, s.conn, s.ebnd, s.elen, cand, np.zeros((nw, 2)),
                        np.tile([0.0, 1.0], (nw, 1)),
                        np.tile([1e13, 2e-5, 5e12, 0.3, 0.95, 0.0], (nw, 1)), np.zeros(nw),
                        wact, np.empty((nw, 8), np.int64), np.empty((nw, 8)),
                        np.empty((nw, 8, 2)), np.empty(nw), np.empty((nw, NRES)), s.m, 0.0)
    floor = {(s.elem_gid[e], s.elem_loc[e]) for e, x in zip(cand, wact, strict=True)
             if x == C_ACTIVE}
    found_floor = {(k[0], k[1]) for k, a in zip(eff.last["keys"], eff.last["active"],
                                                strict=True)
                   if a == C_ACTIVE and k[2] == -2}
    assert floor == found_floor and len(floor) > 0


def test_contact_below_dt_min_names_the_bodies(tmp_path):
    """A contact that needs a step below time.dt_min stops the run naming body and element."""
    from pdfem.errors import SimulationError

    doc = collision(v=20.0, end=4e-6)
    doc["time"]["dt_min"] = 1.0e-8
    with pytest.raises(SimulationError, match=r"limited by contact\.kn0 on the edges of body "
                                              r"\d+ element \d+\) is below time\.dt_min"):
        sim = Simulation(parse_scene(doc, str(tmp_path)), MPI.COMM_SELF)
        while sim.t < sim.t_end:
            sim.step()


def test_per_contact_slip_and_dissipation_of_a_sliding_block(tmp_path):
    """The per-contact output of a block sliding down a frictional incline, over the late
    steps: the wall carries m g cos(theta) on average, a slipping contact is at the friction
    limit and slips at the block's speed, and the dissipation is mu |F_n| v (Coulomb)."""
    theta, mu, g = np.radians(30.0), 0.2, 1.0e4
    sim = Simulation(parse_scene(_incline(theta, mu, g), str(tmp_path)), MPI.COMM_SELF)
    s = sim.store
    weight = s.m.sum() * g * np.cos(theta)
    fn, diss, bound = [], [], []
    while sim.t < sim.t_end:
        sim.step()
        if sim.t < 0.5 * sim.t_end:
            continue
        # The store of this step (a rebuild, called by the block's own motion, makes a new one)
        s = sim.store
        rows = split_rows(contact_rows(sim.state, sim.ctx))
        v = abs((s.m * s.v[:, 0]).sum() / s.m.sum())
        assert (rows["key"][:, 2] < 0).all() and (rows["element"][:, 1] == -1).all()
        assert np.allclose(rows["normal"], [0.0, -1.0])
        fn.append(-rows["force"][:, 0].sum())
        slipping = rows["dissipation"] > 0.0
        f_n, f_s = np.abs(rows["force"][:, 0]), np.abs(rows["force"][:, 1])
        assert (f_s <= mu * f_n * (1 + 1e-12)).all()
        assert np.allclose(f_s[slipping], mu * f_n[slipping], rtol=1e-12)
        assert np.allclose(rows["slip_rate"][slipping], v, rtol=0.05)
        diss.append(rows["dissipation"].sum())
        bound.append(mu * f_n.sum() * v)
        assert (rows["heat"] == 0.0).all()
    assert np.mean(fn) == pytest.approx(weight, rel=0.05)
    assert np.mean(diss) == pytest.approx(np.mean(bound), rel=0.02)


def test_block_candidates_of_a_rebuild_hold_every_later_block_contact(tmp_path):
    """Blocks are searched at the rebuilds, with the skin, their nodes in the rebuild test:
    at every step every block pair whose boxes overlap (the search the step would make) is
    among the candidates, on the small shot-912 bed hit at 1500 m/s (periodic sides) by a
    hammer that starts 0.4 mm above it (only the hammer moves until it arrives)."""
    from pdfem.effects.contact_candidates import block_elements
    from pdfem.tools.study.speeds import packaged_doc, rung_doc

    doc = rung_doc(packaged_doc("small"), 1500.0, "1pt", 1)
    gap = 4.0e-4
    doc["domain"]["box"][3] += gap
    (hammer,) = [b for b in doc["blocks"] if b["name"] == "hammer"]
    hammer["box"][1] += gap
    hammer["box"][3] += gap
    doc["time"]["end"] = 4.0e-7
    sim = Simulation(parse_scene(doc, str(tmp_path)), MPI.COMM_SELF)
    eff = _contact(sim)
    rebuilds = touching = 0
    s, g0 = sim.store, sim.ctx.nglobal
    top = s.x[s.nn_global:, 1].max()
    while sim.t < sim.t_end:
        store = sim.store
        sim.step()
        st, s = sim.state, sim.store
        # Rebuilds while the hammer (the highest block) is still above the bed: its own
        face = max(s.x[s.nstart[b]:s.nstart[b] + s.nn[b], 1].min() for b in range(g0))
        rebuilds += face > top and s is not store
        bbox = np.empty((s.nelem, 4))
        element_bboxes(s.x, s.conn, 0, s.nelem, bbox)
        boxes = np.array([[bbox[e0:e0 + n, 0].min(), bbox[e0:e0 + n, 1].min(),
                           bbox[e0:e0 + n, 2].max(), bbox[e0:e0 + n, 3].max()]
                          for e0, n in zip(s.estart, s.ne, strict=True)])
        pairs = eff.detect._element_pairs(st, sim.ctx, bbox,
                                          eff.detect._block_pairs(st, sim.ctx, boxes, 0.0), 0.0)
        walls, wids = eff.detect._wall_elements(st, sim.ctx, bbox, 0, block_elements(s, g0),
                                                0.0)
        now = {tuple(r) for r in pairs} | {(e, -1 - w, 0) for e, w in zip(walls, wids,
                                                                         strict=True)}
        assert now <= {tuple(r) for r in eff.detect.cand}, f"step {sim.nstep}"
        keys, active = eff.last["keys"], eff.last["active"]
        block = np.isin(keys[:, 0], s.gid[:g0]) | np.isin(keys[:, 2], s.gid[:g0])
        touching += int(((active == C_ACTIVE) & block).any())
    # The hammer moves half the skin before the bed does: rebuilds from its motion alone
    assert rebuilds >= 3 and touching > 100 and len(pairs) > 0
