"""Guards: the last good state of a run, and the remedies a scene may ask for ([guards]).

The checks themselves run inside the step (:meth:`pdfem.solver.Simulation.fail` records the
first failure of a rank, and the time-step reduction every step already does stops every rank
together) or, for the energy balance, in the driver (every ``guards.energy_steps`` steps and
at each energy sample). This module keeps what a failure needs:

- an in-memory copy of the state every ``guards.snapshot_steps`` steps (the owned bodies with
  their contact history, the time-step state, the cell owners and the driver's output
  counters), taken at the end of a step whose checks all passed: the *last good state*;
- :meth:`Guards.rollback`, which puts that state back exactly as a restart from a checkpoint
  would (rebuild of ghosts from the owned bodies, on any number of ranks), so the driver can
  either write it as a checkpoint (``<run file>.ckpt.h5``) or retry from it with half the time
  step (the ``dt_retries`` remedy);
- the ``cap_contact`` remedy (:func:`contact_stiffness_cap`), applied once at set-up.
"""

import math

import numpy as np

from pdfem.kernels import contact_law as L
from pdfem.kernels.contact_law import DT_FACTOR
from pdfem.kernels.stable import q4_stable_dt
from pdfem.parallel.mpi import global_min

# What can help when a check fails, by the name its message starts with ("check NAME: ..."):
# what a restart from the last good state may change, and what needs a new run
ADVICE = {
    "non-finite": ("a smaller time.safety, guards.dt_retries", "[bulk_viscosity]"),
    "inverted element": ("a smaller time.safety, guards.dt_retries",
                         "[bulk_viscosity], contact.damping, another grain mesh "
                         "(element.level, element.rule)"),
    "contact overlap": ("a smaller time.safety, guards.dt_retries",
                        "[bulk_viscosity], contact.damping, a stiffer contact (contact.kn0) or a "
                        "larger contact.delta_max, another grain mesh (element.level, "
                        "element.rule)"),
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


class Snapshot:
    """The state at the end of one good step (every rank holds its owned bodies)."""

    def __init__(self, sim, driver):
        s = sim.store
        self.batch = s.take(np.arange(s.nb_own))
        self.nb_own = s.nb_own
        self.owner = sim.owner.copy()
        self.nstep, self.t, self.dt, self.dt_prev = sim.nstep, sim.t, sim.dt, sim.dt_prev
        self.driver = dict(driver)


class Guards:
    """The [guards] table of a run: snapshots, rollback and the time-step remedy."""

    def __init__(self, sim):
        g = sim.resolved["guards"]
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

    def due(self, sim):
        """True when a snapshot is to be taken after this step."""
        return self.last is None or sim.nstep - self.last.nstep >= self.every

    def keep(self, sim, driver):
        """Keep the current state (the end of a step that passed every check) as last good;
        ``driver`` holds the output counters to restore with it."""
        self.last = Snapshot(sim, driver)

    def rollback(self, sim):
        """Put the last good state back into ``sim`` (collective); return its driver dict."""
        sim.restore(self.last)
        return dict(self.last.driver)

    def can_retry(self):
        """True when the time-step remedy has a retry left."""
        return self.retries_left > 0

    def retry(self, sim, reason):
        """The time-step remedy: back to the last good state, time step and safety halved.
        Returns the driver dict of that state and the line that says what was done."""
        driver = self.rollback(sim)
        self.retries_left -= 1
        old = sim.halve_step()
        n = self.retries - self.retries_left
        line = (f"guard: {reason}; remedy {n} of {self.retries}: back to step {sim.nstep} "
                f"(t={sim.t:.6e} s), time step halved (time.safety {old:g} -> {sim.safety:g})")
        self.actions.append(line)
        return driver, line


def contact_stiffness_cap(sim, contact, kcap=None):
    """The ``cap_contact = "element"`` remedy: lower kn0 and the hardening of every contact law
    so that a contact over a whole boundary edge of the initial meshes is no stiffer than the
    elements' initial stable step allows (contact_law.contact_dt >= that step). Returns
    (cap, log line or None when no law needed it); the same on every rank (global minima).
    A restart passes the cap its run started with (kcap) so that it continues bit-identically."""
    s, n = sim.store, sim.store.ne_own
    if kcap is not None:
        return kcap, _apply_cap(contact, kcap, None)
    dt_el = global_min(sim.comm, q4_stable_dt(s.x, s.conn, s.emat, sim.mat_params, 0, n))
    # Stiffness limit of each boundary edge: contact_dt(m, rigid, k L) >= dt_el
    kcap = math.inf
    for k in range(4):
        on = s.ebnd[:n, k] != 0
        a, b = s.conn[:n, k][on], s.conn[:n, (k + 1) % 4][on]
        if a.shape[0]:
            le = np.hypot(s.x[b, 0] - s.x[a, 0], s.x[b, 1] - s.x[a, 1])
            m = np.minimum(s.m[a], s.m[b])
            kcap = min(kcap, float(((2.0 * DT_FACTOR) ** 2 * m / (dt_el * dt_el * le)).min()))
    kcap = global_min(sim.comm, kcap)
    if not math.isfinite(kcap):
        return None, None
    return kcap, _apply_cap(contact, kcap, dt_el)


def _apply_cap(contact, kcap, dt_el):
    """Lower the contact laws to the stiffness cap; the log line (None when nothing changed)."""
    law = contact.law
    changed = False
    kn0_old = float(law[:, :, L.P_KN0].max())
    for i in range(law.shape[0]):
        for j in range(law.shape[1]):
            row = law[i, j]
            for c in (L.P_KN0, L.P_KS):
                if row[c] > kcap:
                    row[c] = kcap
                    changed = True
            # The hardening stops where the tangent stiffness kn0/(1 - r)^2 reaches the cap
            rc = 1.0 - math.sqrt(row[L.P_KN0] / kcap)
            if rc < row[L.P_RCAP]:
                row[L.P_RCAP] = rc
                changed = True
    contact.kn0_max = float(law[:, :, L.P_KN0].max())
    if not changed or dt_el is None:
        return None
    return (f"guard: remedy cap_contact: contact stiffness capped at {kcap:.4g} Pa/m (kn0 "
            f"{kn0_old:.4g} -> {contact.kn0_max:.4g}, hardening stops at delta/delta_max = "
            f"{float(law[:, :, L.P_RCAP].min()):.4g}) so that contacts keep the elements' "
            f"stable step {dt_el:.4g} s")
