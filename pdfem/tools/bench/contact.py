"""``pdfem bench contact``: contact detection and force time per step on dense beds.

For each bed size (pdfem.tools.bench.beds: level-1 grains, 6 elements each, grown 12 % at start so
that about 3 grain-grain contacts per grain are active) the Simulation is built on a one-rank
communicator (pdfem.parallel.mpi.self_comm), takes two untimed warm-up steps, then ``repeat``
samples of k steps each; per-step figures are medians over the samples. An untimed 100-grain bed
runs first, so numba compile or cache load is excluded everywhere. Contact time is the sum of
the timer phases contact_detection and contact_forces; the step time is the wall time of
``Simulation.step``. The grain-pair candidate search runs at rebuilds, under the migration
phase, and is not part of the contact figures (the rebuild count is printed). Memory per grain
is the growth of the resident set size from before the scene is read to after the timed steps
(freed heap pages returned to the OS first, pdfem.memory.trim), over the grains: what the
running simulation holds, all in. The peak is that of VmHWM (set-up included).
"""

import gc
import statistics
import tempfile
import time

import numpy as np

from pdfem.kernels.contact import C_ACTIVE
from pdfem.memory import trim
from pdfem.tools.bench.beds import bed_scene, inflate_grains
from pdfem.tools.bench.elements import machine

# Warm-up steps before the timed samples
WARMUP = 2
# Grain-steps per sample: k = clamp(GRAIN_STEPS / n, 2, 20) steps
GRAIN_STEPS = 200_000
# Grain growth at start (see pdfem.tools.bench.beds)
INFLATE = 1.12
# Grains of the untimed bed that first loads every kernel and module
PRIME = 100


def rss_bytes(key="VmRSS"):
    """Resident set size of this process [bytes]: VmRSS (now) or VmHWM (peak) of
    /proc/self/status; 0 where that file does not exist."""
    try:
        with open("/proc/self/status") as f:
            for line in f:
                if line.startswith(key + ":"):
                    return int(line.split()[1]) * 1024
    except OSError:
        pass
    return 0


def reset_peak():
    """Reset VmHWM to the current RSS (Linux >= 4.0); False where that is not possible."""
    try:
        with open("/proc/self/clear_refs", "w") as f:
            f.write("5")
        return True
    except OSError:
        return False


def steps_per_sample(n):
    """Steps per timed sample for an n-grain bed: few for big beds, up to 20 for small ones."""
    return int(min(20, max(2, GRAIN_STEPS // n)))


def _contact_effect(sim):
    """The contact effect of a Simulation."""
    return [e for e in sim.effects if e.name == "contact"][0]


def _coordination(eff, n):
    """Grain-grain coordination number (touching grain pairs x 2 / n) of the last step."""
    keys = eff.last["keys"][eff.last["active"] == C_ACTIVE]
    pairs = np.unique(keys[keys[:, 2] >= 0][:, [0, 2]], axis=0).shape[0]
    return 2.0 * pairs / n


def _sample(sim, eff, n, k):
    """Run k steps; per step: step s, detection s, forces s, element pairs evaluated and
    active per grain, element s, and the step's CPU time s (this process)."""
    tm = sim.timers.seconds
    d0, f0, e0 = tm["contact_detection"], tm["contact_forces"], tm["elements"]
    step = active = evaluated = cpu = 0.0
    for _ in range(k):
        t0 = time.perf_counter()
        c0 = time.process_time()
        sim.step()
        cpu += time.process_time() - c0
        step += time.perf_counter() - t0
        # Contact counts, outside the timed call
        active += (eff.last["active"] == C_ACTIVE).sum() / n
        evaluated += eff.last["evaluated"] / n
    return (step / k, (tm["contact_detection"] - d0) / k, (tm["contact_forces"] - f0) / k,
            evaluated / k, active / k, (tm["elements"] - e0) / k, cpu / k)


def _drift_check_s(sim, repeat):
    """Median wall time of the energy-drift guard's per-step work (the fixed-point sums of
    pdfem.energy, which the driver runs every guards.energy_steps steps) [s]."""
    from pdfem.energy import fixed_point_terms

    times = []
    for _ in range(max(repeat, 3)):
        t0 = time.perf_counter()
        fixed_point_terms(sim.state, sim.ctx)
        times.append(time.perf_counter() - t0)
    return statistics.median(times)


def run_contact(n, repeat, material="elastic", yardstick=False):
    """Build an n-grain bed of ``material`` grains (pdfem.tools.bench.beds.MATERIALS), time
    ``repeat`` samples; return a dict of figures (with yardstick, also the contact pass of
    the last step against its C twin, pdfem.tools.bench.pass_yardstick)."""
    from pdfem.parallel.mpi import self_comm
    from pdfem.scene import parse_scene
    from pdfem.solver import Simulation

    trim()
    rss0 = rss_bytes()
    peak_ok = reset_peak()
    with tempfile.TemporaryDirectory() as folder:
        # Scene, bed file, Simulation (grains grown by the init_state hook)
        t0 = time.perf_counter()
        scene = parse_scene(bed_scene(n, folder, inflate=INFLATE, material=material), folder,
                            name="bench-bed")
        sim = Simulation(scene, self_comm(), init_state=inflate_grains(INFLATE))
        setup = time.perf_counter() - t0
    eff = _contact_effect(sim)
    for _ in range(WARMUP):
        sim.step()
    # Timed samples
    k = steps_per_sample(n)
    reb0 = sim.timers.calls["migration"]
    samples = [_sample(sim, eff, n, k) for _ in range(repeat)]
    step, det, frc, evald, act, elem, cpu = (statistics.median(col)
                                             for col in zip(*samples, strict=True))
    share = statistics.median((s[1] + s[2]) / s[0] for s in samples)
    coord = _coordination(eff, n)
    drift = _drift_check_s(sim, repeat)
    yard = None
    if yardstick:
        from pdfem.tools.bench.pass_yardstick import pass_yardstick

        yard = pass_yardstick(sim, repeat)
    # Resident memory after the steps, freed pages returned (what the run holds)
    trim()
    out = {"grains": n, "elements": int(sim.store.ne_own), "steps": k, "step": step, "cpu": cpu,
           "yardstick": yard,
           "detection": det, "forces": frc, "elements_s": elem, "contact": det + frc,
           "share": share, "drift": drift,
           "evaluated": evald, "active": act, "coordination": coord, "setup": setup,
           "rebuilds": sim.timers.calls["migration"] - reb0,
           "rss_per_grain": (rss_bytes() - rss0) / n,
           "peak_per_grain": (rss_bytes("VmHWM") - rss0) / n if peak_ok else float("nan")}
    del sim, scene, eff
    gc.collect()
    return out


def print_contact(sizes, repeat, log=print, material="elastic"):
    """Run the contact benchmark for each bed size and print its table; return the rows."""
    from pdfem.tools.bench.pass_yardstick import print_pass_yardstick

    log(f"pdfem bench contact: dense beds of level-1 {material} grains (6 elements each, 1-point "
        "rule), serial, "
        f"median of {repeat} samples of k steps after {WARMUP} warm-up steps "
        "(numba compile excluded)")
    log(machine())
    rows = []
    head = (f"{'grains':>8}{'elements':>9}{'k':>4}{'step ms':>10}{'detect ms':>11}"
            f"{'forces ms':>11}{'contact ms':>12}{'share %':>9}{'us/grain-step':>15}"
            f"{'pairs/grain':>13}{'contacts/grain':>16}{'coord':>7}{'kB/grain':>10}{'rebuilds':>10}")
    log(head)
    # An untimed small bed first: kernels compiled or loaded, modules imported, pools grown
    run_contact(PRIME, 1, material)
    # One bed per size, smallest first
    for n in sizes:
        r = run_contact(n, repeat, material, yardstick=True)
        rows.append(r)
        log(f"{n:>8}{r['elements']:>9}{r['steps']:>4}{1e3 * r['step']:>10.3f}"
            f"{1e3 * r['detection']:>11.3f}{1e3 * r['forces']:>11.3f}{1e3 * r['contact']:>12.3f}"
            f"{100 * r['share']:>9.1f}{1e6 * r['contact'] / n:>15.3f}{r['evaluated']:>13.2f}"
            f"{r['active']:>16.2f}"
            f"{r['coordination']:>7.2f}{r['rss_per_grain'] / 1024:>10.2f}{r['rebuilds']:>10}")
    log("pairs/grain: element pairs evaluated per step, over the grains (each pair once, wall "
        "contacts included); contacts/grain: the active ones; coord: grains touching a grain")
    # Whole-step time per grain-step, and linearity of the contact time
    for r in rows:
        log(f"step time per grain-step at {r['grains']} grains: "
            f"{1e6 * r['step'] / r['grains']:.3f} us (CPU time {1e6 * r['cpu'] / r['grains']:.3f}"
            f" us; elements "
            f"{1e6 * r['elements_s'] / r['grains']:.3f}, contact "
            f"{1e6 * r['contact'] / r['grains']:.3f}; set-up {r['setup']:.2f} s); memory "
            f"{r['rss_per_grain'] / 1024:.2f} kB/grain resident after the steps, peak "
            f"{r['peak_per_grain'] / 1024:.2f} kB/grain; the energy-drift check "
            f"{1e6 * r['drift'] / r['grains']:.3f} us/grain ({100 * r['drift'] / r['step']:.1f} % "
            "of a step, guards.energy_steps = 1)")
    for r in rows:
        print_pass_yardstick(r["yardstick"], r["grains"], log)
    if len(rows) > 1:
        lo, hi = rows[0], rows[-1]
        ratio = (hi["contact"] / hi["grains"]) / (lo["contact"] / lo["grains"])
        step = (hi["step"] / hi["grains"]) / (lo["step"] / lo["grains"])
        log(f"linearity: per grain-step at {hi['grains']} / at {lo['grains']} grains: contact "
            f"{ratio:.2f}, whole step {step:.2f}")
    return rows
