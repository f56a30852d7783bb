"""``pdfem study hard``: the hard cases (pdfem.tools.study.hard_cases) on 1 and on N ranks.

Started under mpirun with N >= 2 ranks. Each case runs first on rank 0 alone (a communicator
of its own), then on all N ranks; rank 0 then reads both run files and reports, per case:

- status: ``ok``, or the guard that stopped the run (its one-line message);
- the largest energy-balance error over the run (``energy/balance_error``), against 2 %;
- finite: every frame dataset holds only finite numbers;
- the smallest Jacobian at the integration points of the element rule over every element of
  every frame (> 0: none inverted; the guard checks the same every step), the smallest corner
  Jacobian over the element's centre Jacobian (1 for a parallelogram, <= 0 a folded corner: a
  corner of a coarse grain's kite element may fold while its integration points stay valid:
  reported, not a failure), the most elements with a folded corner in one frame, and the
  worst corner-Jacobian ratio of the last frame;
- the contacts' absorbed energy beyond stored, friction and damping (contact_loss) of largest
  magnitude over the run, over the largest energy term: the contacts' share of the balance
  error (pdfem.energy), reported so that the part the contact law plays is visible;
- identical: every dataset of the two run files is bit-for-bit the same;
- the figure the case is about (cells crossed per step, height left after squeezing,
  conduction sub-steps, time step ...).

A case passes when its run completes, the error is at most 2 %, everything is finite, no
Jacobian is <= 0 and the two files are identical.
"""

import math
import os
import time

import h5py
import numpy as np

from pdfem.errors import SimulationError
from pdfem.mesh.quality import corner_jacobians, point_jacobians
from pdfem.parallel.mpi import alone, barrier, broadcast, global_max, global_min
from pdfem.tools.study.hard_cases import CASES

# Largest energy-balance error a hard case may show
ENERGY_TOL = 0.02


# The integration points of the two rules in natural coordinates
GP = 1.0 / math.sqrt(3.0)
RULE_POINTS = {"1pt": [(0.0, 0.0)],
               "2x2": [(-GP, -GP), (GP, -GP), (GP, GP), (-GP, GP)]}


def frame_checks(path):
    """Checks of a run file, a dict: ``finite`` (every frame finite), ``jacobian_min`` (the
    smallest Jacobian at the integration points of the scene's rule over all elements and
    frames), ``corner_fold`` (the smallest corner Jacobian over its element's centre Jacobian,
    likewise; <= 0 a folded corner), ``folded`` (the most elements with a corner Jacobian <= 0
    in one frame), ``elements``, ``jacobian_ratio`` (the worst corner-Jacobian ratio of the
    last frame, nan when a corner is <= 0) and ``energy_error`` (the largest balance error)."""
    import tomllib

    with h5py.File(path, "r") as f:
        finite = all(np.isfinite(f["frames"][k][...]).all() for k in f["frames"])
        conn = f["mesh/conn"][...]
        x = f["frames/x"][...]
        err = float(np.max(f["energy/balance_error"][...]))
        rule = tomllib.loads(f.attrs["scene"]).get("element", {}).get("rule", "1pt")
    jmin = fold = math.inf
    folded = 0
    ratio = math.nan
    for k in range(x.shape[0]):
        jmin = min(jmin, float(point_jacobians(x[k], conn, RULE_POINTS[rule]).min()))
        corner = corner_jacobians(x[k], conn)
        centre = point_jacobians(x[k], conn, [(0.0, 0.0)])[:, 0]
        # Worst corner relative to its element (centre J > 0 wherever jmin > 0 for 1pt)
        rel = corner.min(axis=1) / np.where(centre > 0.0, centre, np.nan)
        fold = min(fold, float(np.nanmin(rel)) if np.isfinite(rel).any() else -math.inf)
        folded = max(folded, int((corner.min(axis=1) <= 0.0).sum()))
        if k == x.shape[0] - 1 and corner.min() > 0:
            ratio = float((corner.max(axis=1) / corner.min(axis=1)).max())
    return {"finite": finite, "jacobian_min": jmin, "corner_fold": fold, "folded": folded,
            "elements": int(conn.shape[0]), "jacobian_ratio": ratio, "energy_error": err}


def contact_loss_share(path):
    """The contact_loss of largest magnitude over the run (signed: < 0 is energy the contact
    law gave back beyond what it stored), over the largest energy term at its sample or at
    t = 0 (the balance's scale)."""
    with h5py.File(path, "r") as f:
        e = f["energy"]
        if "contact_loss" not in e:
            # A run without contact
            return 0.0
        loss = e["contact_loss"][...]
        i = int(np.argmax(np.abs(loss)))
        terms = [t for t in e if t not in ("time", "total", "balance_error")]
        scale = max(abs(float(e[t][j])) for t in terms for j in (0, i))
        return float(loss[i]) / scale if scale > 0 else 0.0


def identical(p1, p2):
    """True when every dataset of two HDF5 files is the same, bit for bit."""
    def load(path):
        out = {}
        with h5py.File(path, "r") as f:
            f.visititems(lambda n, o: out.__setitem__(n, o[()])
                         if isinstance(o, h5py.Dataset) else None)
        return out

    a, b = load(p1), load(p2)
    return sorted(a) == sorted(b) and all(np.array_equal(a[k], b[k]) for k in a)


def case_figure(name, sim):
    """The figure a case is about, from its finished Simulation (words)."""
    s = sim.store
    if name == "fast-migration":
        grid = sim.grid
        speed = float(np.sqrt((s.v[: s.nn_own] ** 2).sum(axis=1)).max()) if s.nn_own else 0.0
        speed = global_max(sim.comm, speed)
        cells = speed * sim.dt_prev / min(grid.hx, grid.hy)
        return f"{cells:.1f} cells per step, rebuilds {sim.timers.calls['migration']}"
    if name == "squeeze-50":
        grain = s.isglobal[s.node_body[: s.nn_own]] == 0
        y = s.x[: s.nn_own][grain, 1]
        lo = global_min(sim.comm, float(y.min()) if y.size else math.inf)
        hi = global_max(sim.comm, float(y.max()) if y.size else -math.inf)
        r = sim.scene.resolved["grains"][0]["axes"][1]
        return f"height {100 * (hi - lo) / (2 * r):.1f} % of the initial"
    if name == "hot-conduction":
        return f"conduction sub-steps per step {sim.heat.nsub}"
    return f"dt {sim.dt_prev:.3g} s"


def run_one(scene, comm, out):
    """Run a scene on comm into out; (status, steps, wall s, case Simulation or None)."""
    from pdfem.driver import run as drive
    from pdfem.solver import Simulation

    t0 = time.perf_counter()
    try:
        sim = Simulation(scene, comm)
        summary = drive(sim, out, quiet=True)
        status, steps = "ok", int(summary["steps"])
    except SimulationError as exc:
        sim, status, steps = None, f"failed: {exc}", 0
    wall = global_max(comm, time.perf_counter() - t0)
    return status, steps, wall, sim


def run_case(name, folder, size, comm):
    """Run one hard case on rank 0 alone and on every rank of comm; the result dict (rank 0;
    None elsewhere)."""
    from pdfem.scene import parse_scene

    builder, what = CASES[name]
    os.makedirs(folder, exist_ok=True)
    # Rank 0 builds the scene (and writes its files), every rank parses the same dict
    doc = builder(folder, size) if comm.rank == 0 else None
    doc = broadcast(comm, doc)
    scene = parse_scene(doc, folder, name=f"hard case {name}")
    out1, outn = os.path.join(folder, f"{name}-1.h5"), os.path.join(folder, f"{name}-n.h5")
    for p in (out1, outn):
        for suffix in ("", ".part", ".ckpt.h5"):
            if comm.rank == 0 and os.path.exists(p + suffix):
                os.remove(p + suffix)
    barrier(comm)
    # One rank, then all
    with alone(comm) as solo:
        if solo is not None:
            status1, _, _, _ = run_one(scene, solo, out1)
    barrier(comm)
    status, steps, wall, sim = run_one(scene, comm, outn)
    figure = case_figure(name, sim) if sim is not None else ""
    if comm.rank != 0:
        return None
    row = {"case": name, "what": what, "ranks": comm.size, "status": status, "steps": steps,
           "wall_s": wall, "figure": figure, "energy_error": math.nan, "finite": False,
           "jacobian_min": math.nan, "corner_fold": math.nan, "folded": 0, "elements": 0,
           "jacobian_ratio": math.nan, "identical": False, "contact_loss": math.nan}
    if status == "ok" and status1 == "ok":
        row.update(frame_checks(outn), identical=identical(out1, outn),
                   contact_loss=contact_loss_share(outn))
    elif status == "ok":
        row["status"] = f"1 rank {status1}"
    row["passed"] = bool(row["status"] == "ok" and row["energy_error"] <= ENERGY_TOL
                         and row["finite"] and row["jacobian_min"] > 0 and row["identical"])
    return row


def print_rows(rows, log=print):
    """The study's table, one line per case."""
    log(f"{'case':<16}{'steps':>8}{'wall s':>8}{'energy %':>10}{'c.loss %':>10}{'J ip > 0':>9}"
        f"{'corner/J0':>10}{'folded':>11}{'J ratio':>9}{'finite':>8}{'1=N ranks':>10}"
        "  figure / status")
    for r in rows:
        ok = "PASS" if r["passed"] else "FAIL"
        tail = r["figure"] if r["status"] == "ok" else r["status"]
        log(f"{r['case']:<16}{r['steps']:>8}{r['wall_s']:>8.1f}"
            f"{100 * r['energy_error']:>10.3f}{100 * r['contact_loss']:>10.2f}"
            f"{str(r['jacobian_min'] > 0):>9}"
            f"{r['corner_fold']:>10.2f}{str(r['folded']) + '/' + str(r['elements']):>11}"
            f"{r['jacobian_ratio']:>9.2f}{str(r['finite']):>8}{str(r['identical']):>10}  "
            f"{ok} {tail}")
