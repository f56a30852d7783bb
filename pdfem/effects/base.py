"""What an effect is: a scene table that, when present, adds arrays and kernel calls.

An effect plugs into named points of the step (see :mod:`pdfem.solver`), every one declared
here as a no-op: ``setup`` once, ``start_work`` at t = 0 of a new run, ``after_rebuild`` when
ghosts and contact candidates were rebuilt, ``before_elements`` ahead of the internal forces,
``contact_forces`` (contact), ``body_force`` after the internal and contact forces, ``heat``
(step 6), ``stable_dt`` for its limit on the step (with ``dt_limiter`` to name it),
``step_minimum`` for a quantity reduced with the time step, and ``energy_terms`` for its
terms of the balance. The solver lists once, at set-up, the effects that override each step
hook (:func:`hook_table`, like LAMMPS's ``setmask``), so a hook no effect uses costs nothing.
A disabled effect is never constructed, so it allocates nothing and runs no kernel.

Every hook receives the state it works on, ``st`` (:class:`pdfem.state.State`: the store of
bodies, t, dt, the per-step arrays f, fc, du, kin, the cell reach, time.safety, and ``fail``
for a failed check), and the run's context, ``ctx`` (:class:`pdfem.context.Context`:
communicator, timers, material table, cell grid, blocks, the heat and contact handles). A
hook adds into the arrays its step point is for (forces into st.f or st.fc, heat through the
heat handle) and writes its own attributes and store fields; it never assigns the state's
time or arrays, and never writes another effect's attributes.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

import numpy as np

from pdfem.energy import declare_terms

if TYPE_CHECKING:
    from pdfem.context import Context
    from pdfem.scene.keys import Section
    from pdfem.state import State
    from pdfem.store import Field


class Effect:
    """Base class: every hook is a no-op; subclasses override the ones they use."""

    name: str = ""
    extra_fields: tuple[Field, ...] = ()  # store fields this effect adds (pdfem.store.Field)
    halo_fields: tuple[str, ...] = ()  # node fields refreshed on ghosts every step
    # Its scene table (a pdfem.scene.keys.Section) and the tables it needs, for an effect
    # added with pdfem.effects.register; the built-in effects' tables are in the schema
    section: Section | None = None
    # What a scene needs for it: the tables it requires (other effects' or its own options'
    # owner), the keys every material must set; check_scene for a rule of its own
    requires: tuple[str, ...] = ()
    material_keys: tuple[str, ...] = ()
    # Its terms of the energy balance (pdfem.energy): (name, role) pairs, role +1 a part of
    # E, -1 subtracted from it, 0 a diagnostic; energy_terms gives their per-body values
    energy: tuple[tuple[str, int], ...] = ()
    # Its frame fields of the run file: name -> (per "node" or "elem", trailing shape per row,
    # None standing for the integration-point count); frame_values gives their rows. Those in
    # frame_defaults are written when the scene does not list output.fields; ``outputs`` are
    # its other entries of output.fields (not frame datasets); ``needs`` says in words what a
    # scene needs for it, for the error naming a field it cannot have
    frame_fields: dict[str, tuple[str, tuple[int | None, ...]]] = {}
    frame_defaults: tuple[str, ...] = ()
    outputs: tuple[str, ...] = ()
    needs: str = ""

    def __init_subclass__(cls, **kwargs: Any) -> None:
        super().__init_subclass__(**kwargs)
        declare_terms(cls.__name__, cls.energy)

    def __init__(self, table: dict[str, Any], scene: Any) -> None:
        self.table = table
        # The log lines of the remedies its set-up applied (pdfem.guards: a run logs them with
        # the guards' own actions and keeps them in its summary)
        self.remedies: list[str] = []

    @classmethod
    def check_scene(cls, resolved: dict[str, Any]) -> None:
        """Raise pdfem.errors.SceneError (naming the key) when the resolved scene breaks a
        rule of this effect beyond ``requires`` and ``material_keys``; called when present."""

    @classmethod
    def present(cls, resolved: dict[str, Any]) -> bool:
        """True when the scene (resolved tables) asks for this effect: by default, when its
        table is there; effects that live in other tables override it."""
        return cls.name in resolved

    def setup(self, st: State, ctx: Context) -> None:
        """Called once after the initial store exists."""

    def after_rebuild(self, st: State, ctx: Context) -> None:
        """Called after migration and the rebuild of ghosts (the store is new)."""

    def before_elements(self, st: State, ctx: Context) -> None:
        """Called ahead of the internal forces of each step."""

    def body_force(self, st: State, ctx: Context) -> None:
        """Add forces into st.f for owned nodes."""

    def heat(self, st: State, ctx: Context) -> None:
        """Step 6 of the loop: advance the temperatures over st.dt."""

    def start_work(self, st: State, ctx: Context) -> None:
        """At t = 0 of a new run (not a restart), after the first forces."""

    def contact_forces(self, st: State, ctx: Context) -> None:
        """Add the contacts' forces into st.fc for owned nodes."""

    def stable_dt(self, st: State, ctx: Context) -> float:
        """This rank's limit on the next time step [s] (np.inf: none)."""
        return np.inf

    def dt_limiter(self, st: State, ctx: Context, dt: float) -> str:
        """Words naming what limits this effect's stable step to dt (for the time.dt_min
        error)."""
        return self.name

    def step_minimum(self, st: State, ctx: Context) -> float:
        """A local quantity this effect needs as its minimum over every rank at the next step
        (np.inf: none). It travels in the time step's reduction at the end of each step
        (:meth:`pdfem.solver.Simulation.next_dt`), so it costs no collective of its own;
        :meth:`set_step_minimum` receives the result. An effect that overrides this is
        listed once at set-up."""
        return np.inf

    def set_step_minimum(self, st: State, ctx: Context, value: float) -> None:
        """Receive the global minimum of :meth:`step_minimum`."""

    def frame_values(self, st: State, ctx: Context, name: str, nodes: np.ndarray,
                     elems: np.ndarray) -> np.ndarray:
        """The rows of its frame field ``name`` for the given local nodes or elements."""
        raise NotImplementedError(f"effect {self.name!r} declares no frame field {name!r}")

    def energy_terms(self, st: State, ctx: Context, out: dict[str, np.ndarray]) -> None:
        """Its per-body energy terms (declared in ``energy``): out maps term name ->
        (nb_own,) array; a declared term left out is zero."""


# The hooks of the step the solver calls through hook_table's lists
STEP_HOOKS: tuple[str, ...] = ("before_elements", "contact_forces", "body_force", "heat",
                               "stable_dt", "step_minimum", "start_work")


def hook_table(effects: list[Effect]) -> dict[str, list[Effect]]:
    """{hook: the effects, in order, whose class overrides it} for every step hook."""
    return {hook: [e for e in effects if getattr(type(e), hook) is not getattr(Effect, hook)]
            for hook in STEP_HOOKS}
