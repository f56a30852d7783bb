"""``pdfem bench job``: the default job's wall time in units of the machine's yardstick.

The yardstick is the whole step of the settled 10^3-grain cap bed of ``bench contact
--material cap --sizes 1000`` (seconds per grain-step, the median of the samples) times a fixed
amount of work, 36 433 steps of 218 grains: the default job's work when the yardstick was set,
kept fixed so that the target does not move when the scene changes. The job is ``mpirun -n 2
python -m pdfem`` (the packaged default scene) run in a scratch folder, or the ``run`` table of
a summary JSON it wrote (``--summary``); the figure is its ``run.wall_s`` over the yardstick,
both measured on this machine, the yardstick in the same session.
"""

import json
import math
import os
import subprocess
import sys
import tempfile

from pdfem.errors import InputError

# The fixed work of the yardstick: steps and grains of the default job when it was set
YARDSTICK_STEPS, YARDSTICK_GRAINS = 36433, 218
# The bed of the yardstick [grains] and the job's target [yardsticks]
YARDSTICK_BED, TARGET = 1000, 2.5


def yardstick(repeat):
    """Seconds per grain-step of the 10^3-grain cap bed's whole step (median of ``repeat``
    samples, after an untimed small bed that compiles or loads the kernels)."""
    from pdfem.tools.bench.contact import PRIME, run_contact

    run_contact(PRIME, 1, "cap")
    r = run_contact(YARDSTICK_BED, repeat, "cap")
    return r["step"] / YARDSTICK_BED


def read_run(path):
    """(wall_s, steps, ranks, phases) of the ``run`` table of a run's summary JSON;
    InputError naming the file and the key when it does not hold them."""
    try:
        with open(path) as f:
            run = json.load(f)["run"]
    except OSError as exc:
        raise InputError(f"--summary: {path}: cannot read it ({exc.strerror})") from None
    except (ValueError, TypeError, KeyError):
        raise InputError(f"--summary: {path}: run: not a run's summary JSON (no run table)"
                         ) from None
    try:
        wall = float(run["wall_s"])
    except (KeyError, TypeError, ValueError):
        raise InputError(f"--summary: {path}: run.wall_s: missing or not a number") from None
    if not (math.isfinite(wall) and wall > 0.0):
        raise InputError(f"--summary: {path}: run.wall_s: {wall!r} is not a positive time")
    return wall, run.get("steps"), run.get("ranks"), run.get("phases") or {}


def run_default_job(log):
    """Run the default scene on 2 ranks in a scratch folder (a child mpirun, its own output
    discarded); return read_run of its summary, or None (said) when it cannot."""
    from pdfem.tools.bench.suite import child_mpi_env, mpirun_command

    cmd = mpirun_command(2)
    if cmd is None:
        log("bench job: no mpirun on PATH, the default job not run")
        return None
    env = child_mpi_env()
    with tempfile.TemporaryDirectory() as folder:
        p = subprocess.run(cmd + [sys.executable, "-m", "pdfem", "run", "-o", "job.h5",
                                  "--quiet"], cwd=folder, capture_output=True, text=True,
                           env=env)
        summary = os.path.join(folder, "job-summary.json")
        if p.returncode != 0 or not os.path.exists(summary):
            why = (p.stderr.strip() or p.stdout.strip())[-300:]
            log(f"bench job: the default job failed (exit {p.returncode}): {why}")
            return None
        return read_run(summary)


def print_job(repeat, summary=None, log=print):
    """Measure the yardstick, run the default job (or read ``summary``), print both and their
    ratio beside the target; return the figures (dict)."""
    from pdfem.tools.bench.elements import machine

    job = read_run(summary) if summary is not None else None
    log(f"pdfem bench job: the default job (mpirun -n 2 python -m pdfem) in yardsticks: "
        f"the {YARDSTICK_BED}-grain cap bed's step (bench contact --material cap --sizes "
        f"{YARDSTICK_BED}, median of {repeat} samples) times {YARDSTICK_STEPS} steps x "
        f"{YARDSTICK_GRAINS} grains")
    log(machine())
    y = yardstick(repeat)
    ref = y * YARDSTICK_STEPS * YARDSTICK_GRAINS
    log(f"yardstick: {1e6 * y:.3f} us per grain-step x {YARDSTICK_STEPS} x {YARDSTICK_GRAINS} "
        f"= {ref:.1f} s")
    if job is None:
        job = run_default_job(log)
        if job is None:
            return {"yardstick_s": ref}
        source = "run now on 2 ranks"
    else:
        source = summary
    wall, steps, ranks, phases = job
    log(f"default job ({source}): {wall:.1f} s, {steps} steps on {ranks} rank(s); phases "
        + ", ".join(f"{k} {float(v):.1f} s" for k, v in phases.items()))
    ratio = wall / ref
    log(f"default job / yardstick = {ratio:.2f} (target <= {TARGET:g}: "
        f"{'met' if ratio <= TARGET else 'not met'})")
    return {"yardstick_s": ref, "job_s": wall, "ratio": ratio}
