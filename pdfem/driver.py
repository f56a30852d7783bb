"""Run a scene to its end time: frames and energy at intervals, progress, the run report."""

import math
import os
import sys
import time

import pdfem
from pdfem.energy import TERMS, balance, balance_scale, fixed_point_terms, global_terms
from pdfem.errors import SimulationError
from pdfem.gauges import Gauges
from pdfem.guards import advice
from pdfem.io.h5out import RunWriter
from pdfem.io.restart import Checkpointer, catch_sigterm
from pdfem.parallel.mpi import broadcast


class Schedule:
    """Output at the first step at or past each multiple of an interval (exact times are
    stored with the data; steps are never shortened to land on them)."""

    def __init__(self, interval):
        self.interval, self.k = interval, 1

    def due(self, t):
        """True (once) when t has reached the next multiple of the interval."""
        if t < self.k * self.interval * (1 - 1e-12):
            return False
        while self.k * self.interval * (1 - 1e-12) <= t:
            self.k += 1
        return True


def run(sim, out_path, quiet=False, log=print):
    """Advance ``sim`` to its end time writing ``out_path``; return the summary dict.

    Checkpoints go to ``<out_path>.ckpt.h5`` every ``output.checkpoint_interval`` of simulated
    time and every ``output.checkpoint_wall`` seconds, and when SIGTERM or SIGUSR1 arrives:
    then the run writes one, leaves the run file as ``<out_path>.part`` for the restart and
    returns with ``summary["stopped"]`` set.
    """
    # SIGTERM caught from the start: one that arrives during set-up still ends in a checkpoint
    with catch_sigterm(sim):
        return _run(sim, out_path, quiet, log)


def _run(sim, out_path, quiet, log):
    """The body of :func:`run`."""
    comm, r = sim.comm, sim.resolved
    out = r["output"]
    interval, e_interval = out["interval"], out["energy_interval"]
    nframes = math.floor(sim.t_end / interval * (1 + 1e-12)) + 2
    # Frame datasets are allocated up front (parallel HDF5): no more than the steps allow
    if sim.max_steps:
        nframes = min(nframes, sim.max_steps + 2)
    frames, samples = Schedule(interval), Schedule(e_interval)
    # Gauge elements: found at t = 0, or the checkpoint's on a restart
    saved, where = None, None
    if sim.restarted:
        saved, where = sim.checkpoint.arrays.get("gauge_sets"), f"--restart: {sim.checkpoint.path}"
    gauges, gsched = Gauges(sim, saved, where), Schedule(out["gauge_interval"])
    ckpt = Checkpointer(sim, out_path, out)
    writer = RunWriter(out_path, sim, nframes, out["fields"],
                       resume=ckpt.resume() if sim.restarted else None)
    rows, ref = [], None
    start = (sim.nstep, sim.t)
    t0 = time.perf_counter()
    last_log = t0
    stopped = False
    first_step = None
    guards = sim.guards

    def counters():
        """The driver's output state, kept with each snapshot of the last good state."""
        return {"nframe": writer.nframe, "frames_k": frames.k, "samples_k": samples.k,
                "gauges_k": gsched.k, "checkpoint_k": ckpt.k, "rows": len(rows),
                "gauge_rows": len(gauges.times)}

    def restore(c):
        """Output state back to a snapshot's (frames after it are overwritten)."""
        writer.nframe, frames.k, samples.k, gsched.k, ckpt.k = (
            c["nframe"], c["frames_k"], c["samples_k"], c["gauges_k"], c["checkpoint_k"])
        del rows[c["rows"]:]
        del gauges.times[c["gauge_rows"]:], gauges.rows[c["gauge_rows"]:]
        guards.sample_scale = _sample_scale(comm, rows, ref, sim.energy_floor)

    # What the remedies did at set-up (said even with quiet, like every remedy)
    if comm.rank == 0:
        for line in guards.actions:
            log(line)
    if sim.restarted:
        rows, ref = ckpt.restore(frames, samples, gsched, gauges, writer, log)
    else:
        # Frame and energy at t = 0
        writer.write_frame(sim)
        if len(gauges):
            gauges.sample(sim)
        terms = global_terms(sim)
        if comm.rank == 0:
            ref = terms
            rows.append(_row(sim.t, terms, ref, sim.energy_floor))
    guards.keep(sim, counters())
    # The t = 0 terms on every rank, for the drift check between samples
    guards.ref = broadcast(comm, ref)
    guards.sample_scale = _sample_scale(comm, rows, ref, sim.energy_floor)
    while sim.t < sim.t_end * (1 - 1e-12):
        if sim.max_steps and sim.nstep >= sim.max_steps:
            break
        try:
            at_end = _step(sim, frames, samples, gsched, gauges, writer, nframes, rows, ref,
                           guards)
        except SimulationError as exc:
            if not guards.can_retry():
                _fail(sim, guards, restore, ckpt, frames, samples, gsched, gauges, writer,
                      rows, ref, exc)
            c, line = guards.retry(sim, str(exc))
            restore(c)
            if comm.rank == 0:
                log(line)
            continue
        if first_step is None:
            # Start-up figure: from the pdfem import to the end of the first step
            first_step = time.perf_counter() - pdfem.STARTED
            if comm.rank == 0 and not quiet:
                log(f"first step at {first_step:.2f} s after start")
        if ckpt.due(at_end):
            with sim.timers.phase("output"):
                ckpt.write(frames, samples, gsched, gauges, writer, rows, ref)
        if guards.due(sim):
            guards.keep(sim, counters())
        if sim.stop_requested and not at_end:
            stopped = True
            break
        now = time.perf_counter()
        if comm.rank == 0 and not quiet and now - last_log > 2.0:
            last_log = now
            _progress(sim, now - t0, rows, log, start)
    # Any other exception skips the collective close: the command line aborts every rank
    if stopped:
        writer.suspend()
    else:
        writer.close(rows, TERMS, ok=True, gauges=gauges)
    wall = time.perf_counter() - t0
    report = sim.timers.report(comm)
    summary = {"steps": sim.nstep, "time": sim.t, "wall_s": wall,
               "balance_error": rows[-1][-1] if rows else None, "stopped": stopped,
               "checkpoint": ckpt.path if stopped else None,
               "phases": report, "effects": sim.effect_names, "ranks": comm.size,
               "imbalance": sim.timers.imbalance(comm), "rebalances": sim.rebalances,
               "remedies": list(guards.actions)}
    if comm.rank == 0 and not quiet:
        _report(summary, log)
    return summary


def _step(sim, frames, samples, gsched, gauges, writer, nframes, rows, ref, guards):
    """One step and its outputs; the energy-drift guard. Returns True at the end time."""
    comm = sim.comm
    sim.step()
    if guards.energy_drift > 0 and guards.energy_steps and sim.nstep % guards.energy_steps == 0:
        with sim.timers.phase("diagnostics"):
            _drift_check(sim, guards)
    at_end = sim.t >= sim.t_end * (1 - 1e-12)
    if (frames.due(sim.t) or at_end) and writer.nframe < nframes:
        with sim.timers.phase("output"):
            writer.write_frame(sim)
    if len(gauges) and (gsched.due(sim.t) or at_end):
        with sim.timers.phase("diagnostics"):
            gauges.sample(sim)
    if samples.due(sim.t) or at_end:
        with sim.timers.phase("diagnostics"):
            terms = global_terms(sim)
            msg = scale = None
            if comm.rank == 0:
                rows.append(_row(sim.t, terms, ref, sim.energy_floor))
                err = rows[-1][-1]
                scale = balance_scale(terms, ref, sim.energy_floor)
                if guards.energy_drift > 0 and not err <= guards.energy_drift:
                    msg = (f"check energy drift: the energy-balance error {err:.3e} exceeds "
                           f"guards.energy_drift = {guards.energy_drift:g}")
            msg, scale = broadcast(comm, (msg, scale))
            guards.sample_scale = max(guards.sample_scale, scale)
            if msg:
                raise SimulationError(f"step {sim.nstep}, t={sim.t:.6e} s: {msg}")
    return at_end


def _sample_scale(comm, rows, ref, floor):
    """The largest balance scale of the energy samples after t = 0 in rows (rank 0's), on
    every rank; 0.0 when there is none."""
    scale = 0.0
    if comm.rank == 0:
        scale = max([balance_scale(dict(zip(TERMS, r[1:1 + len(TERMS)], strict=True)), ref,
                                   floor) for r in rows if r[0] > 0.0] + [0.0])
    return broadcast(comm, scale)


def _drift_check(sim, guards):
    """The energy-drift guard between samples: the balance of the fixed-point sums (the same
    figure, hence the same decision, on every rank and any rank count). It starts after the
    first sample past t = 0: in the first steps of a scene that starts at rest every term is
    tiny, and the leapfrog's start-up mismatch of kinetic and potential energy is a large
    fraction of them (a quarter at step 1 of a bed falling from rest)."""
    if not guards.sample_scale > 0.0:
        return
    terms = fixed_point_terms(sim)
    # The samples' largest scale joins the floor: the scale is never below it
    floor = max(sim.energy_floor, guards.sample_scale)
    err = math.inf if terms is None else balance(terms, guards.ref, floor)[1]
    if not err <= guards.energy_drift:
        raise SimulationError(f"step {sim.nstep}, t={sim.t:.6e} s: check energy drift: the "
                              f"energy-balance error {err:.3e} exceeds guards.energy_drift = "
                              f"{guards.energy_drift:g}")


def _fail(sim, guards, restore, ckpt, frames, samples, gsched, gauges, writer, rows, ref, exc):
    """A failed check with no remedy left: the last good state becomes the checkpoint (the
    run file stays as <path>.part for a restart from it); raise the error, extended."""
    restore(guards.rollback(sim))
    with sim.timers.phase("output"):
        ckpt.write(frames, samples, gsched, gauges, writer, rows, ref)
    writer.suspend()
    help_ = advice(str(exc))
    raise SimulationError(f"{exc}; the last good state (step {sim.nstep}, t={sim.t:.6e} s) "
                          f"is in {ckpt.path}: change the scene and continue with --restart "
                          f"{ckpt.path}" + (f"; {help_}" if help_ else "")) from None


def _row(t, terms, ref, floor):
    total, err = balance(terms, ref, floor)
    return [t] + [terms[k] for k in TERMS] + [total, err]


def _progress(sim, wall, rows, log, start):
    """One progress line; ``start`` = (step, time) where this session began."""
    step0, t0 = start
    # Fraction of this session's work done: by time, or by steps under time.max_steps
    frac = (sim.t - t0) / (sim.t_end - t0) if sim.t_end > t0 else 1.0
    if sim.max_steps:
        frac = max(frac, (sim.nstep - step0) / max(sim.max_steps - step0, 1))
    eta = wall * (1 - frac) / frac if frac > 0 else float("nan")
    err = rows[-1][-1] if rows else float("nan")
    line = (f"step {sim.nstep}  t={sim.t:.4e} s  dt={sim.dt:.3e} s  "
            f"{(sim.nstep - step0) / wall:.0f} steps/s  ETA {eta:.0f} s  energy err {err:.2e}")
    if _terminal():
        print("\r" + line, end="", flush=True)
    else:
        log(line)


def _report(summary, log):
    if _terminal():
        print()
    if summary["stopped"]:
        log(f"stopped by SIGTERM or SIGUSR1 at step {summary['steps']}, t={summary['time']:.6e} s: "
            f"checkpoint {summary['checkpoint']}; continue with --restart "
            f"{summary['checkpoint']}")
    word = "stopped" if summary["stopped"] else "done"
    log(f"{word}: {summary['steps']} steps to t={summary['time']:.6e} s in "
        f"{summary['wall_s']:.2f} s on {summary['ranks']} rank(s); energy balance error "
        f"{summary['balance_error']:.3e}; effects: {', '.join(summary['effects']) or 'none'}")
    log(f"load imbalance (max/mean busy time over ranks): {summary['imbalance']:.3f}; "
        f"rebalanced {summary['rebalances']} time(s)")
    log("phase                 min [s]    avg [s]    max [s]")
    for p, (lo, avg, hi) in summary["phases"].items():
        if hi > 0:
            log(f"{p:<20} {lo:10.3f} {avg:10.3f} {hi:10.3f}")


def _terminal():
    """A progress line that rewrites itself only on a real terminal: not under mpirun,
    which hands the ranks a pseudo-terminal and joins the rewritten lines."""
    return sys.stdout.isatty() and "OMPI_COMM_WORLD_SIZE" not in os.environ \
        and "PMI_RANK" not in os.environ
