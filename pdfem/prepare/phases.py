"""The rain route of ``pdfem prepare``: rain grains into the chamber, drop a weight on them,
relax, settle; save the bed.

Four phases, each a full Simulation of a scene derived from the preparation scene:

1. rain: the grains of :func:`pdfem.prepare.rain.rain_grains` fall under the amplified gravity
   ``prepare.gravity`` with damping ``prepare.damping``; moduli are scaled by
   ``prepare.stiffness_scale`` (elastic grains) and contact kn0, ks by ``contact_scale``,
   which lengthens the stable step by 1/sqrt(scale);
2. weight: the block ``prepare.weight`` is placed ``drop_gap`` above the highest grain and
   released at ``drop_velocity``; same accelerations;
3. relax: the weight and gravity are removed and the bed unloads, still with the packing
   stiffnesses and without friction (which would lock contact forces in), until it is at rest;
4. settle: the scene's own materials and contact stiffness take over, with every density
   scaled by ``prepare.mass_scale`` (mass scaling: a longer stable step, the same static
   equilibrium since no body force acts) and damping kept, until the bed is at rest again: the
   impact scene starts from an equilibrium of its own materials and contacts. This phase runs
   at most SETTLE_STEPS steps.
Each phase starts from rest with zero grain stresses; the bed file keeps the settle phase's
stresses and material state, so the impact scene starts in that equilibrium (the shear
history of frictional contacts is not kept).

A phase ends at the first check (every CHECK steps, after at least MIN_STEPS) where the
kinetic energy is below ``ke_fraction`` x M g H (M the grains' mass, g the amplified gravity,
H the chamber height), or at ``phase_time``. Every decision uses exact global sums, so the
bed is the same bit for bit on any number of ranks.
"""

import copy
import math
import os
import time
import tomllib

import numpy as np

from pdfem.energy import global_terms
from pdfem.errors import InputError
from pdfem.io.bedfile import write_bed
from pdfem.limits import check_step_count
from pdfem.parallel.mpi import barrier, broadcast, gather_objects
from pdfem.prepare import packing
from pdfem.prepare.rain import rain_grains
from pdfem.scene import check_ranks, parse_scene
from pdfem.scene.schema import HEAT_EFFECTS
from pdfem.solver import Simulation

# Steps between kinetic-energy checks, and the fewest steps of a phase
CHECK = 100
MIN_STEPS = 1000
# The most steps of the settle phase (it only confirms the equilibrium), and the step limit
# of the other phases (none: prepare.phase_time ends them)
SETTLE_STEPS = 50000
NO_LIMIT = 2**62
# Tables of the preparation scene that the phases drop (analysis, heat, output)
DROPPED = ("prepare", "shock", "gauges", "output", "grains_file", "heat", "thermal_bc")


def _base_doc(path, scene):
    """The raw TOML of the preparation scene without the tables the phases do not use."""
    with open(path, "rb") as fh:
        doc = tomllib.load(fh)
    if doc.get("grains") or "grains_file" in doc:
        raise InputError(f"{path}: grains: a preparation scene makes its own grains ([prepare]); "
                         "remove [[grains]] and [grains_file]")
    for key in DROPPED + HEAT_EFFECTS:
        doc.pop(key, None)
    doc["output"] = {"path": os.devnull}
    return doc


def _phase_doc(base, pr, phase, grains, bed_path, weight_box):
    """The scene of one phase (see the module docstring)."""
    doc = copy.deepcopy(base)
    mat = pr["material"]
    weight = pr["weight"]
    # Grains: generated rows, or the bed of the previous phase
    if grains is not None:
        doc["grains"] = [{"center": [float(g[0]), float(g[1])], "axes": [float(g[2]),
                          float(g[3])], "angle": float(g[4]), "material": mat} for g in grains]
    else:
        doc["grains_file"] = {"path": bed_path, "material": mat}
    # The weight takes part in phase 2 only
    blocks = [b for b in doc.get("blocks", []) if b["name"] != weight or phase == "weight"]
    for b in blocks:
        if b["name"] == weight:
            b["box"] = weight_box
            b["velocity"] = [0.0, -pr["drop_velocity"]]
    doc["blocks"] = blocks
    keep = {b["name"] for b in blocks}
    doc["bc"] = [c for c in doc.get("bc", []) if c.get("body", "") in keep or "wall" in c]
    doc["damping"] = {"gamma": pr["damping"]}
    doc["time"] = dict(doc["time"], end=pr["phase_time"])
    if phase in ("relax", "settle"):
        doc.pop("gravity", None)
    if phase == "settle":
        # Mass scaling: the scene's materials, heavier
        for m in doc["materials"].values():
            m["density"] = pr["mass_scale"] * m["density"]
        return doc
    if phase == "relax" and "contact" in doc:
        # Frictionless unloading: a jammed frictional bed would keep contact forces locked in
        doc["contact"]["friction"] = 0.0
        for p in doc["contact"].get("pairs", {}).values():
            p["friction"] = 0.0
    # Packing accelerations: amplified gravity, scaled elastic moduli and contact stiffness
    doc["gravity"] = {"g": [0.0, -pr["gravity"]]}
    s = pr["stiffness_scale"]
    doc["materials"] = {name: {"model": "elastic", "density": m["density"],
                               "bulk": s * m["bulk"], "shear": s * m["shear"]}
                        for name, m in doc["materials"].items()}
    s = pr["contact_scale"]
    if "contact" in doc:
        c = doc["contact"]
        c["kn0"] = s * c.get("kn0", 1.0e15)
        if "ks" in c:
            c["ks"] = s * c["ks"]
        for p in c.get("pairs", {}).values():
            for key in ("kn0", "ks"):
                if key in p:
                    p[key] = s * p[key]
    return doc


def _gather_grains(sim):
    """(gids, nodes, velocities, stresses, material states) of every grain in gid order,
    on rank 0: arrays (n, nn, 2), (n, nn, 2), (n, ne, nip, 4), (n, ne, nip, nst)."""
    s = sim.store
    own = np.nonzero(s.isglobal[: s.nb_own] == 0)[0]
    nodes = [slice(s.nstart[b], s.nstart[b] + s.nn[b]) for b in own]
    elems = [slice(s.estart[b], s.estart[b] + s.ne[b]) for b in own]
    mine = (s.gid[own], [s.x[k] for k in nodes], [s.v[k] for k in nodes],
            [s.sig[k] for k in elems], [s.mst[k] for k in elems])
    parts = gather_objects(sim.comm, mine)
    if sim.comm.rank != 0:
        return None
    gids = np.concatenate([p[0] for p in parts])
    order = np.argsort(gids)
    cols = [[a for p in parts for a in p[j]] for j in range(1, 5)]
    return (gids[order],) + tuple(np.array([c[k] for k in order]) for c in cols)


def wrap_into_box(nodes, box):
    """Periodic sides: move each grain's nodes (n, nn, 2) by whole box widths so that its
    centroid lies in [x0, x1) (a grain that drifted out through one side, as its image)."""
    x0, x1 = box[0], box[2]
    shift = np.floor((nodes[:, :, 0].mean(axis=1) - x0) / (x1 - x0)) * (x1 - x0)
    nodes[:, :, 0] -= shift[:, None]


def _run_phase(name, scene, comm, threshold, log, max_steps, where, allow_huge=False):
    """Step one phase until the kinetic energy is below threshold; return (sim, figures).
    A phase without a step limit of its own is refused beyond MAX_STEPS (pdfem.limits, the
    error naming ``where``) unless ``allow_huge``."""
    t0 = time.perf_counter()
    sim = Simulation(scene, comm)
    if max_steps >= NO_LIMIT:
        check_step_count(sim, where, allow_huge, key="prepare.phase_time")
    ke = math.inf
    while sim.t < sim.t_end and sim.nstep < max_steps:
        sim.step()
        if sim.nstep >= MIN_STEPS and sim.nstep % CHECK == 0:
            terms = global_terms(sim.state, sim.ctx)
            ke = broadcast(comm, terms["kinetic"] if comm.rank == 0 else None)
            if ke < threshold:
                break
    done = ke < threshold
    fig = {"steps": sim.nstep, "time": sim.t, "wall_s": time.perf_counter() - t0,
           "energy": ke, "converged": bool(done)}
    if comm.rank == 0:
        log(f"prepare: {name}: {sim.nstep} steps, t = {sim.t:.4e} s, energy "
            f"{ke:.3e} J/m (threshold {threshold:.3e}) in {fig['wall_s']:.1f} s"
            + ("" if done else "  NOT AT REST at the phase limit (prepare.phase_time"
                                 + (f" or {max_steps} steps)" if max_steps < NO_LIMIT else ")")))
    return sim, fig


def prepare_rain(path, scene, out, comm, log, allow_huge=False):
    """Run the four phases of the preparation scene at ``path``; write the bed to ``out``;
    return its attributes on rank 0. With ``prepare.packing`` the packing reached must be
    within the tolerances of it, else InputError (and no bed file). A phase of more than
    MAX_STEPS estimated steps (pdfem.limits) is refused unless ``allow_huge``: the rain phase
    before any step; the others, whose stable step is about the rain phase's, at their
    start."""
    r = scene.resolved
    pr = r["prepare"]
    base = _base_doc(path, scene)
    box = r["domain"]["box"]
    others = [b for b in r["blocks"] if b["name"] != pr["weight"]]
    floor = max([box[1]] + [b["box"][3] for b in others])
    wbox = next(b["box"] for b in r["blocks"] if b["name"] == pr["weight"])
    rows = rain_grains(pr["grains"], pr["seed"], pr["semi_axis"], pr["aspect"], box[0], box[2],
                       floor, box[3])
    rho = r["materials"][pr["material"]]["density"]
    mass = rho * math.pi * float(np.sum(rows[:, 2] * rows[:, 3]))
    threshold = pr["ke_fraction"] * mass * pr["gravity"] * (box[3] - box[1])
    level = r["element"]["level"]
    phases = ("rain", "weight", "relax", "settle")
    figs, tmp = {}, [f"{out}.{p}.h5" for p in phases[:-1]]
    try:
        state, grains, bed, weight_box = None, rows, None, wbox
        for k, phase in enumerate(phases):
            if phase == "weight":
                top = broadcast(comm, float(state[1][:, :, 1].max()) if comm.rank == 0 else None)
                y0 = top + pr["drop_gap"]
                weight_box = [wbox[0], y0, wbox[2], y0 + wbox[3] - wbox[1]]
                if weight_box[3] > box[3]:
                    raise InputError(f"prepare.weight: the weight does not fit above the bed "
                                     f"(needs y up to {weight_box[3]:g} m, domain top "
                                     f"{box[3]:g} m)")
            doc = _phase_doc(base, pr, phase, grains, bed, weight_box)
            where = f"{path} ({phase} phase)"
            sc = parse_scene(doc, scene.base_dir, name=where)
            check_ranks(sc, comm.size, where)
            limit = SETTLE_STEPS if phase == "settle" else NO_LIMIT
            sim, figs[phase] = _run_phase(phase, sc, comm, threshold, log, limit, where,
                                          allow_huge)
            state = _gather_grains(sim)
            if comm.rank == 0 and r["domain"]["periodic"] == "x":
                wrap_into_box(state[1], box)
            bed, grains = (tmp[k] if k < len(tmp) else out), None
            err = None
            if comm.rank == 0:
                attrs = {"level": level, "phase": phase}
                if phase == "settle":
                    fig, err = _bed_figures(state, level, box, floor, rho, figs, pr, log)
                    attrs.update(fig, scene=scene.to_toml_string())
            err = broadcast(comm, err)
            if err:
                raise InputError(err)
            if comm.rank == 0:
                ell = np.concatenate([state[1].mean(axis=1), rows[:, 2:]], axis=1)
                # The last phase's stresses and material state travel with the bed
                last = phase == "settle"
                write_bed(bed, ell, state[1], np.zeros_like(state[2]), attrs,
                          state[3] if last else None, state[4] if last else None)
            barrier(comm)
    finally:
        if comm.rank == 0:
            for p in tmp:
                if os.path.exists(p):
                    os.remove(p)
    return _report(out, figs, comm, log)


def _bed_figures(state, level, box, floor, rho, figs, pr, log):
    """Attributes of the settled bed (packing between the floor and the highest grain node,
    residual stresses, phase figures) and the packing check's complaint (None: fine)."""
    nodes, stress = state[1], state[3]
    prof = packing.profile(packing.outlines(nodes, level), box[0], box[2], floor,
                           float(nodes[:, :, 1].max()))
    target = pr.get("packing")
    for line in packing.report(prof, target):
        log(f"prepare: {line}")
    press = -(stress[..., 0] + stress[..., 1] + stress[..., 3]) / 3.0
    out = {"method": "rain", **packing.attributes(prof, target, rho), "seed": pr["seed"],
           "converged": all(f["converged"] for f in figs.values()),
           "residual_pressure_mean": float(press.mean()),
           "residual_stress_max": float(np.abs(stress).max())}
    for name, f in figs.items():
        for key, val in f.items():
            out[f"{name}_{key}"] = val
    err = packing.check(prof, target, pr["tolerance"], pr["slice_tolerance"],
                        "prepare.packing")
    return out, (err + " (the rain route packs densely; method = \"geometric\" reaches a "
                 "chosen packing)" if err else None)


def _report(out, figs, comm, log):
    """Print the bed's figures (rank 0) and return them."""
    if comm.rank != 0:
        return None
    import h5py

    with h5py.File(out, "r") as f:
        a = dict(f.attrs)
    log(f"prepare: bed {out}: height {a['bed_top'] - a['bed_bottom']:.4e} m, bed density "
        f"{a['bed_density']:.1f} kg/m^3 (grain density x packing {a['packing_whole']:.4f}); "
        f"residual grain pressure {a['residual_pressure_mean']:.3e} Pa mean, largest stress "
        f"component {a['residual_stress_max']:.3e} Pa; wall time "
        f"{sum(f['wall_s'] for f in figs.values()):.1f} s")
    return a
