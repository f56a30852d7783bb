"""Run a scene to its end time: frames and energy at intervals, progress, the run report."""

import math
import os
import sys
import time

import pdfem
from pdfem.energy import balance, fixed_point_terms
from pdfem.errors import SimulationError
from pdfem.guards import advice
from pdfem.io.restart import catch_sigterm
from pdfem.output import RunOutput
from pdfem.parallel.mpi import broadcast, global_sum


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
    """The body of :func:`run`: the outer loop of steps, remedies, checkpoints and stop."""
    comm, guards = sim.comm, sim.guards
    output = RunOutput(sim, out_path, log)
    start = (sim.nstep, sim.t)
    t0 = time.perf_counter()
    last_log = t0
    stopped = False
    first_step = None
    # What the remedies did at set-up (said even with quiet, like every remedy)
    if comm.rank == 0:
        for line in guards.actions:
            log(line)
    guards.keep(sim.state, sim.owner, output.snapshot())
    # The t = 0 terms on every rank, for the drift check between samples
    guards.ref = broadcast(comm, output.ref)
    guards.sample_scale = output.sample_scale()
    while sim.t < sim.t_end * (1 - 1e-12):
        if sim.max_steps and sim.nstep >= sim.max_steps:
            break
        try:
            at_end = _step(sim, output)
        except SimulationError as exc:
            if not guards.can_retry():
                _fail(sim, output, exc)
            # The time-step remedy: back to the last good state, time step and safety halved
            last = guards.use_retry()
            sim.restore(last)
            old = sim.halve_step()
            line = guards.retried(str(exc), sim.nstep, sim.t, old, sim.safety)
            output.restore(last.driver)
            if comm.rank == 0:
                log(line)
            continue
        if first_step is None:
            # Start-up figure: from the pdfem import to the end of the first step
            first_step = time.perf_counter() - pdfem.STARTED
            if comm.rank == 0 and not quiet:
                log(f"first step at {first_step:.2f} s after start")
        if output.ckpt.due(at_end):
            output.checkpoint()
        if guards.due(sim.nstep):
            guards.keep(sim.state, sim.owner, output.snapshot())
        if sim.stop_requested and not at_end:
            stopped = True
            break
        now = time.perf_counter()
        if comm.rank == 0 and not quiet and now - last_log > 2.0:
            last_log = now
            _progress(sim, now - t0, output.rows, log, start)
    # Any other exception skips the collective close: the command line aborts every rank
    if stopped:
        output.suspend()
    else:
        output.close()
    wall = time.perf_counter() - t0
    report = sim.timers.report(comm)
    summary = {"steps": sim.nstep, "time": sim.t, "wall_s": wall,
               "balance_error": output.balance_error(), "stopped": stopped,
               "checkpoint": output.ckpt.path if stopped else None,
               "phases": report, "effects": sim.effect_names, "ranks": comm.size,
               "imbalance": sim.timers.imbalance(comm), "rebalances": sim.rebalances,
               "remedies": list(guards.actions), "skipped_at_rest": _skipped(sim, comm)}
    if comm.rank == 0 and not quiet:
        _report(summary, log)
    return summary


def _skipped(sim, comm):
    """Share of the 2x2 element updates of the run skipped at rest, over all ranks (None with
    the 1-point rule, which computes every element, or with element.skip_rest = false)."""
    if sim.rest is None:
        return None
    n = global_sum(comm, sim.element_steps)
    return global_sum(comm, int(sim.rest.sum())) / n if n > 0 else 0.0


def _step(sim, output):
    """One step, the energy-drift guard between samples, and the step's output. Returns
    True at the end time."""
    guards = sim.guards
    sim.step()
    if guards.energy_drift > 0 and guards.energy_steps and sim.nstep % guards.energy_steps == 0:
        with sim.timers.phase("diagnostics"):
            _drift_check(sim, guards)
    at_end = sim.t >= sim.t_end * (1 - 1e-12)
    output.end_of_step(at_end)
    return at_end


def _drift_check(sim, guards):
    """The energy-drift guard between samples: the balance of the fixed-point sums (the same
    figure, hence the same decision, on every rank and any rank count). It starts after the
    first sample past t = 0: in the first steps of a scene that starts at rest every term is
    tiny, and the leapfrog's start-up mismatch of kinetic and potential energy is a large
    fraction of them (a quarter at step 1 of a bed falling from rest)."""
    if not guards.sample_scale > 0.0:
        return
    terms = fixed_point_terms(sim.state, sim.ctx)
    # The samples' largest scale joins the floor: the scale is never below it
    floor = max(sim.energy_floor, guards.sample_scale)
    err = math.inf if terms is None else balance(terms, guards.ref, floor)[1]
    if not err <= guards.energy_drift:
        raise SimulationError(f"step {sim.nstep}, t={sim.t:.6e} s: check energy drift: the "
                              f"energy-balance error {err:.3e} exceeds guards.energy_drift = "
                              f"{guards.energy_drift:g}")


def _fail(sim, output, exc):
    """A failed check with no remedy left: the last good state becomes the checkpoint (the
    run file stays as <path>.part for a restart from it); raise the error, extended."""
    last = sim.guards.last
    sim.restore(last)
    output.restore(last.driver)
    output.checkpoint()
    output.suspend()
    help_ = advice(str(exc))
    raise SimulationError(f"{exc}; the last good state (step {sim.nstep}, t={sim.t:.6e} s) "
                          f"is in {output.ckpt.path}: change the scene and continue with "
                          f"--restart {output.ckpt.path}" + (f"; {help_}" if help_ else "")
                          ) from None


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
    if summary["skipped_at_rest"] is not None:
        log(f"element updates skipped at rest (unmoved, unloaded): "
            f"{100 * summary['skipped_at_rest']:.1f} %")
    log("phase                 min [s]    avg [s]    max [s]")
    for p, (lo, avg, hi) in summary["phases"].items():
        if hi > 0:
            log(f"{p:<20} {lo:10.3f} {avg:10.3f} {hi:10.3f}")


def _terminal():
    """A progress line that rewrites itself only on a real terminal: not under mpirun,
    which hands the ranks a pseudo-terminal and joins the rewritten lines."""
    return sys.stdout.isatty() and "OMPI_COMM_WORLD_SIZE" not in os.environ \
        and "PMI_RANK" not in os.environ
