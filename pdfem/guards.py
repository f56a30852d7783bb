"""Guards: the last good state of a run, and the remedies a scene may ask for ([guards]).

The checks themselves run inside the step (:meth:`pdfem.solver.Simulation.fail` records the
first failure of a rank, and the time-step reduction every step already does stops every rank
together) or, for the energy balance, in the driver (every ``guards.energy_steps`` steps and
at each energy sample). This module keeps what a failure needs:

- an in-memory copy of the state every ``guards.snapshot_steps`` steps (the owned bodies with
  their contact history, the time-step state, the cell owners and the driver's output
  counters), taken at the end of a step whose checks all passed: the *last good state*;
- the ``dt_retries`` remedy's count (:meth:`Guards.use_retry`) and the lines saying what the
  remedies did. The driver puts the last good state back into the stepper
  (:meth:`pdfem.solver.Simulation.restore`, exactly as a restart from a checkpoint would:
  ghosts rebuilt from the owned bodies, on any number of ranks) and either writes it as a
  checkpoint (``<run file>.ckpt.h5``) or retries from it with half the time step;
- the ``cap_contact`` remedy is the contact's (:mod:`pdfem.effects.contact_cap`), applied once by
  its own set-up; an effect's set-up remedies (``Effect.remedies``) join the actions here.
"""


# What can help when a check fails, by the name its message starts with ("check NAME: ..."):
# what a restart from the last good state may change, and what needs a new run
ADVICE = {
    "non-finite": ("a smaller time.safety, guards.dt_retries", "[bulk_viscosity]"),
    "inverted element": ("a smaller time.safety, guards.dt_retries",
                         "[bulk_viscosity], contact.damping, another grain mesh "
                         "(element.mesh, element.level, element.rule), an equation of state "
                         "for a crystal at GPa (eos)"),
    "contact overlap": ("a smaller time.safety, guards.dt_retries",
                        "[bulk_viscosity], contact.damping, a stiffer contact (contact.kn0) or a "
                        "larger contact.delta_max, another grain mesh (element.mesh, "
                        "element.level, element.rule), an equation of state for a crystal at "
                        "GPa (eos)"),
    "time step": ("a smaller time.dt_min",
                  "[bulk_viscosity], contact.damping, guards.cap_contact where the contact "
                  "stiffness is a numerical penalty"),
    "energy drift": ("a smaller time.safety, guards.dt_retries, a larger guards.energy_drift "
                     "where the drift is understood", ""),
    "conduction sub-steps": ("a smaller time.safety",
                             "a coarser grain mesh (element.level), a lower conductivity"),
}


def advice(message):
    """'what can help: ...' for the failed check named in ``message``, or ''."""
    for name, (restart, new_run) in ADVICE.items():
        if f"check {name}:" in message:
            return "what can help: " + "; ".join(
                [f"on restart {restart}"] + ([f"in a new run {new_run}"] if new_run else []))
    return ""


class LastGood:
    """The last good state of the guards: the state's snapshot at the end of one good step
    (every rank holds its owned bodies), the cell owners and the output's counters."""

    def __init__(self, st, owner, output):
        self.state = st.snapshot()
        self.owner = owner.copy()
        self.nstep = self.state.nstep
        self.driver = dict(output)


class Guards:
    """The [guards] table of a run (``table``): the last good state, the time-step remedy's
    retries and what the remedies did. The driver acts on them: it keeps a state, and on a
    failed check puts the last good one back into the stepper (and halves the step)."""

    def __init__(self, table):
        g = table
        self.energy_drift = g["energy_drift"]
        self.energy_steps = g["energy_steps"]
        # The t = 0 terms, on every rank, for the drift check between samples (driver), and
        # the largest balance scale of the samples after t = 0 (0: none yet, the check waits)
        self.ref = None
        self.sample_scale = 0.0
        self.every = g["snapshot_steps"]
        self.retries_left = g["dt_retries"]
        self.retries = g["dt_retries"]
        self.last = None
        self.actions = []

    def due(self, nstep):
        """True when a snapshot is to be taken after step ``nstep``."""
        return self.last is None or nstep - self.last.nstep >= self.every

    def keep(self, st, owner, output):
        """Keep the state ``st`` (the end of a step that passed every check) as last good,
        with the cell owners and ``output``, the output's counters to restore with it."""
        self.last = LastGood(st, owner, output)

    def can_retry(self):
        """True when the time-step remedy has a retry left."""
        return self.retries_left > 0

    def use_retry(self):
        """Spend one retry of the time-step remedy; returns the last good state to go back
        to."""
        self.retries_left -= 1
        return self.last

    def retried(self, reason, nstep, t, old_safety, safety):
        """Record a retry (back at step ``nstep``, time ``t``, time.safety ``old_safety`` ->
        ``safety``); returns the line that says what was done."""
        n = self.retries - self.retries_left
        line = (f"guard: {reason}; remedy {n} of {self.retries}: back to step {nstep} "
                f"(t={t:.6e} s), time step halved (time.safety {old_safety:g} -> {safety:g})")
        self.actions.append(line)
        return line
