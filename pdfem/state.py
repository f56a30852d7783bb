"""The state a step advances, with one owner: the bodies, the time and the per-step arrays.

A :class:`State` is what the stepper (:class:`pdfem.solver.Simulation`) changes from one step
to the next and nothing else: the store of bodies (owned, global and ghost), the time t, the
step count, the lengths of the last and the next step, the per-step arrays sized to the
store (nodal forces f, their contact part fc, the step's position increments du and the
bodies' kinetic energies kin), the cell reach of the last rebuild (what the contact search
reaches), time.safety as the time-step remedy left it, and the step's pending failure (the
first failed check of this rank, :meth:`State.fail`). The per-step arrays are made in one place,
:meth:`State.fresh_arrays`, after set-up, a rebuild or a rollback. The stepper writes the
state; effects, guards and io read it (and add into the force arrays in their hooks).

A :class:`Snapshot` is the state at the end of a step that passed every check: the owned
bodies (with their contact history) and the scalars. :meth:`State.from_snapshot` makes a
state of it, with the ghosts rebuilt, as a restart from a checkpoint would.
"""

import numpy as np

from pdfem.store import Store


class Snapshot:
    """The owned bodies of a state and its time-step scalars, copied."""

    def __init__(self, state):
        s = state.store
        self.fields = s.fields
        self.batch = s.take(np.arange(s.nb_own))
        self.nb_own = s.nb_own
        self.t, self.nstep, self.dt, self.dt_prev = state.t, state.nstep, state.dt, \
            state.dt_prev


class State:
    """Bodies, time and per-step arrays of a run on one rank (see the module docstring).

    ``contact``: whether the scene has contact (then fc has a row per node; otherwise it is
    (0, 2), which the integrator reads as "no contact work to account").
    """

    def __init__(self, store, contact, safety=1.0, reach=1):
        self.contact = contact
        self.store = store
        self.t, self.nstep = 0.0, 0
        # No step has a length before the first next_dt: set-up evaluates forces at dt = 0
        self.dt = self.dt_prev = 0.0
        # The step's factor on the stable step, and the cells the contact search reaches
        # around a grain's cell (set at each rebuild: pdfem.parallel.exchange.cell_reach)
        self.safety, self.reach = safety, reach
        # The first failed check of the step on this rank ("": none)
        self.failure = ""
        self.fresh_arrays()

    def fail(self, msg):
        """Record a failed check (the first of the step counts); every rank stops at the end
        of the step (pdfem.solver.Simulation.next_dt)."""
        if not self.failure:
            self.failure = msg

    def fresh_arrays(self):
        """The per-step arrays sized to the store, zeroed: forces f, contact forces fc, step
        increments du, kinetic energies kin (the one place they are made)."""
        s = self.store
        self.f = np.zeros_like(s.v)
        self.fc = np.zeros_like(s.v) if self.contact else np.zeros((0, 2))
        self.du = np.zeros_like(s.v)
        self.kin = np.zeros(s.nbody)

    def new_store(self, store):
        """A rebuilt store (migration, new ghosts): the per-step arrays follow it."""
        self.store = store
        self.fresh_arrays()

    def snapshot(self):
        """A :class:`Snapshot` of this state."""
        return Snapshot(self)

    @classmethod
    def from_snapshot(cls, snap, contact, rebuild, safety):
        """The state of a snapshot: its owned bodies with the ghosts ``rebuild`` (a function
        of the owned store returning the store with its ghosts and the cell reach) makes, its
        time and step lengths, per-step arrays fresh, no failure; ``safety`` the present one
        (a rollback keeps what the remedy set)."""
        store, reach = rebuild(Store(snap.fields, snap.batch, snap.nb_own))
        st = cls(store, contact, safety, reach)
        st.t, st.nstep, st.dt, st.dt_prev = snap.t, snap.nstep, snap.dt, snap.dt_prev
        return st
