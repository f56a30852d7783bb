"""``pdfem bench parallel``: what halo refresh and migration cost on several ranks.

Run under mpirun (``bench all`` starts it as ``mpirun -n 2``). The bed is the benchmark bed
of pdfem.tools.bench.beds (cap grains, 6 elements each) with ``per_rank`` grains per rank, split in
strips. Two runs of the same bed:

- as the scene sets it (neighbour-list skin 0.2 r0): the halo refresh every step and the
  rebuilds (migration) as they come;
- with a skin of 1e-12 m, so that every step is a rebuild: the cost of one migration.

Per phase the slowest rank's time is taken (it sets the pace). Figures: halo and migration
as fractions of the step; the halo cost per boundary cell of a rank (the input of the
scaling model in docs/performance.md); the same ranks' load imbalance. Printed on rank 0.
"""

import statistics
import tempfile
import time

import numpy as np

from pdfem.parallel.mpi import array_max, barrier, broadcast, global_max, world
from pdfem.tools.bench.beds import bed_scene, inflate_grains
from pdfem.tools.bench.contact import INFLATE
from pdfem.tools.bench.elements import machine

# Warm-up steps and timed steps per sample
WARMUP = 3
STEPS = 10


def bed_simulation(comm, n, skin=None):
    """Simulation of an n-grain benchmark bed on comm, strips partition, skin overridden."""
    from pdfem.scene import parse_scene
    from pdfem.solver import Simulation

    folder = tempfile.mkdtemp(prefix="pdfem-bench-") if comm.rank == 0 else None
    folder = broadcast(comm, folder)
    text = None
    if comm.rank == 0:
        text = bed_scene(n, folder, inflate=INFLATE, material="cap")
    text = broadcast(comm, text)
    text = text.replace("[domain]", '[domain]\npartition = "strips"', 1)
    if skin is not None:
        text = "\n".join(f"skin = {skin!r}" if ln.startswith("skin =") else ln
                         for ln in text.splitlines())
    barrier(comm)
    scene = parse_scene(text, folder, name="bench-parallel")
    return Simulation(scene, comm, init_state=inflate_grains(INFLATE))


def _sample(sim, comm, k):
    """k steps: per-step (wall, halo, migration) seconds of the slowest rank, rebuild count."""
    tm = sim.timers.seconds
    h0, m0, r0 = tm["halo"], tm["migration"], sim.timers.calls["migration"]
    barrier(comm)
    t0 = time.perf_counter()
    for _ in range(k):
        sim.step()
    wall = time.perf_counter() - t0
    loc = np.array([wall, tm["halo"] - h0, tm["migration"] - m0])
    loc = array_max(comm, loc)
    return loc / k, sim.timers.calls["migration"] - r0


def _boundary_cells(sim):
    """Cells of this rank with a cell of another rank in their 3x3 block (max over ranks)."""
    g, own = sim.grid, sim.owner
    ix, iy = np.arange(g.ncell) % g.nx, np.arange(g.ncell) // g.nx
    mine = own == sim.comm.rank
    edge = np.zeros(g.ncell, bool)
    for dy in (-1, 0, 1):
        for dx in (-1, 0, 1):
            jx, jy = np.clip(ix + dx, 0, g.nx - 1), np.clip(iy + dy, 0, g.ny - 1)
            edge |= own[jx + g.nx * jy] != sim.comm.rank
    return int(global_max(sim.comm, int((mine & edge).sum())))


def run_parallel(per_rank, repeat, comm=None):
    """Time the bed on comm's ranks; a dict of figures (same on every rank)."""
    comm = comm or world()
    n = per_rank * comm.size
    out = {"ranks": comm.size, "grains": n}
    for label, skin in (("normal", None), ("forced", 1e-12)):
        sim = bed_simulation(comm, n, skin)
        for _ in range(WARMUP):
            sim.step()
        samples = [_sample(sim, comm, STEPS) for _ in range(repeat)]
        per = [s[0] for s in samples]
        out[label] = {
            "step": statistics.median(p[0] for p in per),
            "halo": statistics.median(p[1] for p in per),
            "migration": statistics.median(p[2] for p in per),
            "rebuilds": sum(s[1] for s in samples),
            "steps": STEPS * repeat,
        }
        if label == "normal":
            out["boundary_cells"] = _boundary_cells(sim)
            out["imbalance"] = sim.timers.imbalance(comm)
        del sim
    return out


def print_parallel(per_rank, repeat, log=print):
    """Run the parallel benchmark; print its figures on rank 0; return the dict."""
    comm = world()
    r = run_parallel(per_rank, repeat, comm)
    if comm.rank != 0:
        return r
    nm, fo = r["normal"], r["forced"]
    halo = nm["halo"] / nm["step"]
    mig_step = fo["migration"]
    log(f"pdfem bench parallel: {r['grains']} cap grains (6 elements each) on {r['ranks']} ranks "
        f"({per_rank} per rank, strips), median of {repeat} samples of {STEPS} steps; "
        "per phase the slowest rank")
    log(machine().replace("one core", f"{r['ranks']} ranks"))
    log(f"step {1e3 * nm['step']:.2f} ms, halo refresh {1e3 * nm['halo']:.3f} ms "
        f"({100 * halo:.1f} % of the step), migration {1e3 * nm['migration']:.3f} ms per step "
        f"over {nm['steps']} steps with {nm['rebuilds']} rebuilds; load imbalance "
        f"{r['imbalance']:.3f}")
    log(f"a rebuild every step (skin 1e-12 m): step {1e3 * fo['step']:.2f} ms, migration "
        f"{1e3 * mig_step:.2f} ms = {100 * mig_step / fo['step']:.1f} % of that step, "
        f"{mig_step / nm['step']:.2f} normal steps")
    per_cell = nm["halo"] / max(r["boundary_cells"], 1)
    log(f"halo cost per boundary cell: {1e6 * per_cell:.2f} us per step "
        f"({r['boundary_cells']} boundary cells on the busiest rank)")
    r["halo_fraction"] = halo
    r["overhead"] = (nm["halo"] + nm["migration"]) / nm["step"]
    r["per_cell"] = per_cell
    log(f"parallel overhead (halo + migration) / step: {100 * r['overhead']:.1f} % "
        "(target <= 10 %)")
    return r
