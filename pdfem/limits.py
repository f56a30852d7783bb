"""Limits on the work a command starts: a valid input whose estimate is absurd is refused
before anything runs or is written, with the estimate, unless the user passes --allow-huge.

A typo (time.end in seconds meant as microseconds, a bed in metres meant as millimetres) makes
a valid scene that would run for days. Every command that starts simulations estimates their
size first, cheaply, and raises an :class:`~pdfem.errors.InputError` naming the file, the key
and the estimate:

- steps (``run``, ``sweep``, ``study accuracy``, the rain phases of ``prepare``): the time
  left over the first global stable step, or time.max_steps when that is smaller, above
  MAX_STEPS. Even a scene of a few grains takes about 0.3 ms a step on the 2-vCPU machine
  (8 rained grains and two blocks: 43 700 steps in 11.5 s), so 1e9 steps are days;
- prepared beds (``prepare``, ``study width``): the grain count and the work of the
  preparation (:mod:`pdfem.prepare.size`).

Sizes that no run can hold (grains, cells or block elements above 1e7) are refused by the
scene checks (:mod:`pdfem.scene`), with no way around them.
"""

import gc
import math

from pdfem.errors import InputError

# Steps beyond which a run is refused unless --allow-huge
MAX_STEPS = 10**9
# What a refusal tells the user to do when the work is meant
ALLOW = "pass --allow-huge if you mean it"


def add_allow_huge(parser, what):
    """Add the --allow-huge option to a command's parser; ``what`` ends its help text."""
    parser.add_argument("--allow-huge", action="store_true", help="start even when the "
                        f"estimated work is absurd ({what})")


def check_step_count(sim, name, allow_huge=False, key="time.end", remedy=None):
    """Refuse (InputError naming ``name`` and ``key``, what sets the end time) a run whose
    estimated step count, the time left over the first stable step (or time.max_steps when
    smaller), exceeds MAX_STEPS, unless ``allow_huge``; ``remedy`` (default: shorten key or
    set time.max_steps) says what to change. The step is the global one, so every rank
    decides alike."""
    # Python floats: a tiny step gives inf, not numpy's overflow warning
    left = float(sim.t_end - sim.t) / float(sim.dt) if sim.dt > 0 else math.inf
    steps = min(left, sim.max_steps - sim.nstep) if sim.max_steps else left
    if steps > MAX_STEPS and not allow_huge:
        remedy = remedy or f"shorten {key}, set time.max_steps"
        raise InputError(f"{name}: {key}: about {steps:.3g} steps of {sim.dt:.3g} s to reach "
                         f"{sim.t_end:g} s, more than {MAX_STEPS:.0e}: {remedy}, or {ALLOW}")


def check_runs(runs, comm, allow_huge=False, key="time.end", remedy=None):
    """Check the step count of every run of a plan before the first one starts.

    ``runs``: (scene, name) pairs; each scene's :class:`~pdfem.solver.Simulation` is set up
    on ``comm`` in turn (its first stable step is the estimate's), checked and dropped, so
    the plan costs one more set-up per run and never more than one run's memory. Raises the
    InputError of :func:`check_step_count` (``name`` naming the file and the run; ``key``
    and ``remedy`` as there) for the first run over MAX_STEPS; nothing is written. A run
    whose set-up already stops on a guard (SimulationError, on every rank together) is
    passed over: it stops the same way when its turn comes, and the command deals with it
    as it does then.
    """
    if allow_huge:
        return
    from pdfem.errors import SimulationError
    from pdfem.solver import Simulation

    for scene, name in runs:
        try:
            sim = Simulation(scene, comm)
        except SimulationError:
            continue
        try:
            check_step_count(sim, name, key=key, remedy=remedy)
        finally:
            del sim
            gc.collect()
