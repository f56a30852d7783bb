"""The step loop. Read :meth:`Simulation.step` top to bottom: it is the architecture's list.

1. positions to t+dt (eq. 72)
2. neighbourhood: rebuild (migrate + ghosts) when a node moved more than half the skin,
   otherwise refresh the ghosts' positions and velocities (and temperatures)
3. internal forces of owned elements (strain increment -> material -> stress -> forces);
   effects with element temperatures prepare them first (before_elements)
4. contact forces on owned nodes (effect hook; contact heat with it)
5. body forces (effect hooks); boundary conditions and damping enter step 7
6. heat: sources onto the nodes, temperatures to t+dt (effect hook)
7. next dt (global min), velocities to the next half step (eq. 68), diagnostics, output
"""

import numpy as np

from partition import CellGrid, needs_rebalance
from pdfem import build, setup
from pdfem.context import Context
from pdfem.effects import active_effects, find
from pdfem.effects.base import hook_table
from pdfem.effects.contact import Contact, check_contact_scene
from pdfem.effects.damping import Damping
from pdfem.effects.heat import Heat
from pdfem.energy import energy_floor, initial_strain_work, run_terms
from pdfem.errors import SimulationError
from pdfem.guards import Guards
from pdfem.kernels.checks import first_nonfinite
from pdfem.kernels.element import q4_forces_2x2
from pdfem.kernels.element_1pt import (
    HG_BENDING,
    HG_COEFFICIENT,
    HG_COLS,
    HG_COLS_POINTS,
    HG_FULL,
    HG_POINTS,
    q4_forces_1pt,
)
from pdfem.kernels.integrate import NACC, advance_positions, advance_velocities, moves_half_skin
from pdfem.kernels.params import EOS_G
from pdfem.kernels.stable import q4_stable_dt
from pdfem.memory import trim
from pdfem.mesh.quality import corner_jacobians
from pdfem.parallel.exchange import cell_reach, rebuild
from pdfem.parallel.mpi import (
    allgather_objects,
    array_max,
    global_any,
    global_min,
)
from pdfem.parallel.owners import cell_owners, owned_cell_weights
from pdfem.state import State
from pdfem.store import core_fields
from pdfem.timers import Timers

# Element temperatures of a run without thermo-mechanical coupling (the kernels skip them)
NO_ETH = np.zeros((0, 3))


class Simulation:
    """One run of a scene on a communicator: setup, :meth:`step`, :meth:`run`."""

    def __init__(self, scene, comm, init_state=None, restart=None):
        r = scene.resolved
        self.scene, self.comm, self.resolved = scene, comm, r
        self.timers = Timers()
        self._effects(r, scene)
        self._elements(r)
        self._controls(r, scene, restart)
        self.state = self._first_state(scene, init_state, restart)
        self._set_up_effects(r)
        self._start(restart)

    # ------------------------------------------------------------------ set-up, in steps
    def _effects(self, r, scene):
        """The effects the scene asks for, their energy terms and the handles the step calls."""
        check_contact_scene(r)
        self.effects = active_effects(r, scene)
        self.effect_names = [e.name for e in self.effects]
        # The run's energy terms: the core terms and the effects' (pdfem.energy.run_terms)
        self.terms = run_terms(self.effects)
        # The temperature field's owner (None without [heat]): the handle the contact heat
        # and the diagnostics use
        self.heat = find(self.effects, Heat)
        # The contact (None without [contact]): its stiffness cap is kept for a restart
        self.contact = find(self.effects, Contact)
        damping = find(self.effects, Damping)
        self.gamma = damping.gamma if damping is not None else 0.0

    def _elements(self, r):
        """The material table, the element rule and its kernel, the store's fields."""
        self.mat_params = build.material_table(r["materials"])
        self.nst = build.check_materials(r["materials"], self.mat_params)
        self.mat_ids = {name: i for i, name in enumerate(r["materials"])}
        el = r["element"]
        self.nip = 1 if el["rule"] == "1pt" else 4
        self.element_kernel = q4_forces_1pt if el["rule"] == "1pt" else q4_forces_2x2
        # The 2x2 rule's count of elements skipped at rest, and of the element updates it was
        # asked for (None: the 1-point rule, or element.skip_rest = false: nothing is skipped)
        self.rest = (np.zeros(1, np.int64) if el["skip_rest"] and el["rule"] == "2x2"
                     else None)
        self.element_steps = 0
        # The 1-point rule's hourglass spring: its modulus and coefficient
        kind = el["hourglass_stiffness"]
        self.hg_model = {"bending": HG_BENDING, "full": HG_FULL,
                         "points": HG_POINTS}.get(kind, HG_COEFFICIENT)
        self.hg_coef = 0.0
        if el["rule"] == "1pt":
            self.hg_coef = float(el["hourglass"]) if kind == "coefficient" else 1.0
        self.fields = core_fields(self.nip, self.nst, NACC,
                                  HG_COLS_POINTS if self.hg_model == HG_POINTS else HG_COLS)
        for eff in self.effects:
            self.fields += [f for f in eff.extra_fields if f not in self.fields]
        self.halo_fields = ["x", "v"] + [n for e in self.effects for n in e.halo_fields]
        # Element temperatures exist (store field eth) when heat couples into the elements
        self.coupled = any(f.name == "eth" for f in self.fields)
        # A Mie-Gruneisen material is heated by the bulk viscosity (its elements' qv)
        self.heats_eos = (bool(np.any(self.mat_params[:, EOS_G] > 0.0))
                          and any(f.name == "qv" for f in self.fields))
        # Without it the 1-point kernel takes None (compiled without the thermal branches)
        self.no_eth = None if el["rule"] == "1pt" else NO_ETH

    def _controls(self, r, scene, restart):
        """The domain and its cell grid, the time controls, the global layout, the flags."""
        dom, tm, el = r["domain"], r["time"], r["element"]
        self.box = tuple(dom["box"])
        self.grid = CellGrid(self.box, dom["cell_size"], dom["periodic"] == "x")
        self.skin = dom["skin"]
        self.t_end = tm["end"]
        self.dt_max, self.dt_min, self.max_steps = tm["dt_max"], tm["dt_min"], tm["max_steps"]
        self.layout = build.Layout(scene.grains["center"].shape[0], el["level"],
                                   r.get("blocks", []), el["mesh"])
        self.has_contact = "contact" in r
        self.rebalances = 0
        self.restarted = restart is not None
        # Stop and checkpoint requests: local flags, shared by the reduction of next_dt
        self.stop_requested = self.checkpoint_requested = False
        self.local_stop = self.local_ckpt = 0.0

    def _first_state(self, scene, init_state, restart):
        """The first state: its bodies from the scene or the checkpoint on their cell owners,
        with their ghosts, the blocks and boundary conditions, the cell reach, time.safety."""
        store, self.owner, blocks, self.bcs = setup.initial_bodies(self, scene, init_state)
        self.blocks, self.nglobal = blocks, len(blocks)
        # Periodic sides: each block's left and right node columns move as one
        self.partner = np.zeros(0, np.int64)
        if self.grid.periodic_x and self.nglobal:
            self.partner = build.tied_nodes(blocks.sets, store.nstart[: self.nglobal],
                                            store.nn_global)
        with self.timers.phase("migration"):
            store, self.halo, reach = self.rebuild(store)
        self.checkpoint = None
        safety = self.resolved["time"]["safety"]
        if restart is not None:
            store, self.owner, self.checkpoint = setup.restart_bodies(self, restart)
            with self.timers.phase("migration"):
                store, self.halo, reach = self.rebuild(store)
            store = setup.drop_restart_forces(store, self.fields, self.checkpoint)
            # A time step the remedy halved stays halved unless the scene asks for less
            safety = min(safety, self.checkpoint.state.get("safety", safety))
        return State(store, self.has_contact, safety, reach)

    def _set_up_effects(self, r):
        """The context, the effects' set-up, the step hooks, the guards and their remedies."""
        # What the effects' hooks read besides the state
        self.ctx = Context(self)
        for eff in self.effects:
            eff.setup(self.state, self.ctx)
        # The effects that use each step hook, listed once
        self.hooks = hook_table(self.effects)
        self.minima = self.hooks["step_minimum"]
        self.guards = Guards(r["guards"])
        for eff in self.effects:
            self.guards.actions.extend(eff.remedies)
        self.energy_floor = energy_floor(self.state, self.ctx)
        # The set-up's temporaries are freed: give their pages back to the OS
        trim()

    def _start(self, restart):
        """Continue exactly where a checkpoint stopped, or: the forces at t = 0, the energy
        accumulators of the t = 0 state and the first half step."""
        st = self.state
        if restart is not None:
            ck = self.checkpoint.state
            st.t, st.nstep, st.dt, st.dt_prev = ck["t"], ck["nstep"], ck["dt"], ck["dt_prev"]
            self.guards.retries_left = min(self.guards.retries,
                                           ck.get("dt_retries_left", self.guards.retries))
            # The contact forces of the step before, for a frame written at the restart
            saved = self.checkpoint.contact_force
            if saved is not None and st.fc.shape[0]:
                st.fc[: st.store.nn_own] = saved
            self.refresh_reductions()
            return
        initial_strain_work(st, self.ctx)
        self.compute_forces()
        for eff in self.hooks["start_work"]:
            eff.start_work(st, self.ctx)
        st.dt_prev = 0.0
        st.dt = self.next_dt()
        self.advance_velocities(first=True)

    # ------------------------------------------------------------------ the state, read
    # The state's fields by name, for effects, guards and io (read-only: the state's owner,
    # this stepper, is the one that moves them)
    store = property(lambda self: self.state.store, doc="The bodies (pdfem.store.Store).")
    t = property(lambda self: self.state.t, doc="Time [s].")
    safety = property(lambda self: self.state.safety, doc="time.safety as the remedy left it.")
    reach = property(lambda self: self.state.reach, doc="Cell reach of the last rebuild.")
    contact_cap = property(
        lambda self: self.contact.stiffness_cap if self.contact is not None else None,
        doc="The contact stiffness cap of the cap_contact remedy (None: none), for a restart.")
    dt = property(lambda self: self.state.dt, doc="Length of the next step [s].")
    dt_prev = property(lambda self: self.state.dt_prev, doc="Length of the last step [s].")
    nstep = property(lambda self: self.state.nstep, doc="Steps taken.")
    f = property(lambda self: self.state.f, doc="Nodal forces of the step (nn, 2) [N/m].")
    fc = property(lambda self: self.state.fc, doc="Their contact part ((0, 2): no contact).")
    du = property(lambda self: self.state.du, doc="Position increments of the step [m].")
    kin = property(lambda self: self.state.kin, doc="Kinetic energy per body [J/m].")

    # ------------------------------------------------------------------ the step
    def step(self):
        """Advance one time step (see the module docstring for the order)."""
        st = self.state
        s = st.store
        # 1. positions to t + dt
        with self.timers.phase("integration"):
            advance_positions(s.x, s.v, st.dt, s.nn_own, st.du)
            st.t += st.dt
            st.nstep += 1
        # 2. neighbourhood: rebuild or halo refresh
        self.neighbourhood()
        # 3-5. internal, contact and body forces
        self.compute_forces()
        # 6. heat
        for eff in self.hooks["heat"]:
            eff.heat(st, self.ctx)
        # 7. next dt, velocities, diagnostics
        st.dt_prev = st.dt
        st.dt = self.next_dt()
        self.advance_velocities()

    def neighbourhood(self):
        """Rebuild ghosts and migrate when the last step's reduction said that this step's
        position update may move a node half the skin (:meth:`next_dt`)."""
        st = self.state
        if self.rebuild_next:
            with self.timers.phase("migration"):
                self._rebalance()
                store, self.halo, st.reach = self.rebuild(st.store)
            st.new_store(store)
            for eff in self.effects:
                eff.after_rebuild(st, self.ctx)
        else:
            with self.timers.phase("halo"):
                self.halo.refresh([getattr(st.store, n) for n in self.halo_fields])
        # Step increments of ghosts are derived exactly as their owners computed them (in
        # place: no array made per step)
        np.multiply(st.store.v, st.dt, out=st.du)

    def restore(self, last):
        """Back to a last good state of the guards (:class:`pdfem.guards.LastGood`)
        (collective): the state of its snapshot with the ghosts rebuilt on its cell owners,
        the effects told, the reductions redone."""
        self.owner = last.owner.copy()

        def ghosts(store):
            store, self.halo, reach = self.rebuild(store)
            return store, reach

        with self.timers.phase("migration"):
            self.state = st = State.from_snapshot(last.state, self.has_contact, ghosts,
                                                  self.state.safety)
        self.stop_requested = False
        for eff in self.effects:
            eff.after_rebuild(st, self.ctx)
        self.refresh_reductions()

    def halve_step(self):
        """The time-step remedy: time step and time.safety halved; returns the old safety."""
        st = self.state
        old = st.safety
        st.safety *= 0.5
        st.dt *= 0.5
        return old

    def request_stop(self):
        """Ask every rank to stop after this step (a signal; shared by the next reduction)."""
        self.local_stop = 1.0

    def request_checkpoint(self):
        """Ask every rank to checkpoint after the next step (shared by its reduction)."""
        self.local_ckpt = 1.0

    def checkpoint_done(self):
        """A checkpoint was written: the request is answered."""
        self.checkpoint_requested = False

    def rebuild(self, store):
        """Migrate grains to their cells' owners and rebuild the ghosts of a ``store``, with
        the cell reach of its grains (collective); returns (store, halo, reach): the reach is
        the state's, for the contact candidates (:func:`pdfem.parallel.exchange.cell_reach`)."""
        reach, wide = cell_reach(self.comm, store, self.grid, self.nglobal, self.skin)
        # Periodic sides: no grain may reach round the box to itself (a pair that meets
        # through both sides is a failed check of the contact detection)
        if self.grid.periodic_x and not wide + self.skin < self.grid.period:
            raise SimulationError(f"a grain {wide:.4g} m wide with the skin {self.skin:.4g} m "
                                  f"spans the box's width {self.grid.period:.4g} m: with "
                                  "periodic sides it would meet itself; widen domain.box")
        store, halo = rebuild(self.comm, store, self.grid, self.owner, self.nglobal, reach)
        return store, halo, reach

    def _rebalance(self):
        """At a rebuild: new cell owners when the element-count load of the ranks is more
        than domain.rebalance times its mean. Every rank computes the same exact integer
        weights, so all agree; results do not depend on ownership (bit-identical)."""
        threshold = self.resolved["domain"]["rebalance"]
        if threshold <= 0.0 or self.comm.size == 1:
            return
        s = self.store
        weights = owned_cell_weights(self.comm, s, self.grid, self.nglobal,
                                     s.ne[self.nglobal: s.nb_own])
        if needs_rebalance(weights, self.owner, self.comm.size, threshold):
            self.owner = cell_owners(self.resolved["domain"]["partition"], weights, self.grid,
                                     self.comm.size)
            self.rebalances += 1

    def compute_forces(self):
        """Residual force f = P - I on owned nodes: elements, contact, body forces."""
        st = self.state
        s = st.store
        st.f[:] = 0.0
        for eff in self.hooks["before_elements"]:
            eff.before_elements(st, self.ctx)
        with self.timers.phase("elements"):
            args = (s.x, self.du, s.conn, s.emat, self.mat_params, s.sig, s.mst, s.hourglass,
                    self.hg_model, 0, s.ne_own, self.f, s.ewint, s.ewp,
                    s.eth if self.coupled else self.no_eth)
            # The elements' viscosity only for a material it heats (the kernels' default else)
            heat = (s.qv,) if self.heats_eos else ()
            if self.nip == 1:
                bad = self.element_kernel(*args, st.dt, *heat)
            elif self.rest is None:
                bad = self.element_kernel(*args, None, st.dt, *heat)
            else:
                # Elements at rest and unloaded are skipped from the first step on (every
                # element is computed, and checked, at t = 0)
                bad = self.element_kernel(*args, self.rest if st.nstep > 0 else None, st.dt,
                                          *heat)
                self.element_steps += s.ne_own
        if bad >= 0:
            self.fail(self._element_failure(bad))
        if self.has_contact:
            # The contacts' forces go to fc (their work is accounted per body), then to f
            st.fc[:] = 0.0
            for eff in self.hooks["contact_forces"]:
                eff.contact_forces(st, self.ctx)
            st.f += st.fc
        for eff in self.hooks["body_force"]:
            eff.body_force(st, self.ctx)
        self._check_finite()

    def _element_failure(self, e):
        """Words for an element the kernel stopped at: which check failed."""
        s = self.store
        jac = corner_jacobians(s.x, s.conn[e : e + 1])[0]
        what = (f"is inverted (corner Jacobians {', '.join(f'{j:.3g}' for j in jac)} m^2)"
                if jac.min() <= 0.0 else "is inverted at an integration point or its material "
                "update failed")
        return f"check inverted element: element {s.elem_loc[e]} of body {s.elem_gid[e]} {what}"

    def _check_finite(self):
        """Guard: a NaN or inf in the owned nodal forces (any bad position, velocity, stress
        or contact ends up there) or temperatures."""
        s = self.store
        bad = first_nonfinite(self.f, s.nn_own)
        what = "force"
        if bad < 0 and self.heat is not None:
            bad = first_nonfinite(s.T.reshape(-1, 1), s.nn_own)
            what = "temperature"
        if bad >= 0:
            b = s.node_body[bad]
            self.fail(f"check non-finite: the {what} of node {bad - s.nstart[b]} of body "
                      f"{s.gid[b]} is not finite")

    def next_dt(self):
        """Global stable step times the safety factor, clipped to the next event; guards."""
        s = self.store
        dt_loc = q4_stable_dt(s.x, s.conn, s.emat, self.mat_params, s.sig, 0, s.ne_own)
        limiter = "the element wave speed"
        for eff in self.hooks["stable_dt"]:
            d = eff.stable_dt(self.state, self.ctx)
            if d < dt_loc:
                dt_loc, limiter = d, eff
        st = self.state
        if not dt_loc > self.dt_min and not st.failure:
            if not isinstance(limiter, str):
                limiter = limiter.dt_limiter(self.state, self.ctx, dt_loc)
            self.fail(f"check time step: the stable dt {dt_loc:.3e} s (limited by {limiter}) is "
                      f"below time.dt_min {self.dt_min:.3e} s")
        # Whether the next step's position update may move a grain node half the skin: the
        # next step is at most this rank's limit, so a bound decides before the reduction
        dt_up = min(st.safety * dt_loc, self.dt_max)
        ahead = self._moves_half_skin(dt_up, 0.5 * (self.dt_prev + dt_up))
        # One reduction: the step, the fail, stop, checkpoint and rebuild flags, the effects'
        # minima
        red = np.array([-dt_loc, 1.0 if st.failure else 0.0, self.local_stop,
                        self.local_ckpt, float(ahead)]
                       + [-e.step_minimum(self.state, self.ctx) for e in self.minima])
        red = array_max(self.comm, red)
        self.rebuild_next = bool(red[4] > 0)
        for e, value in zip(self.minima, red[5:], strict=True):
            e.set_step_minimum(self.state, self.ctx, -value)
        self.stop_requested = self.stop_requested or red[2] > 0
        self.checkpoint_requested = self.checkpoint_requested or red[3] > 0
        self.local_ckpt = 0.0
        if red[1] > 0:
            msgs = [m for m in allgather_objects(self.comm, st.failure) if m]
            raise SimulationError(f"step {self.nstep}, t={self.t:.6e} s: {msgs[0]}")
        dt_stable = -red[0]
        # No clipping to output times: an abrupt change of dt would spoil the energy identity
        return min(st.safety * dt_stable, self.dt_max)

    def _moves_half_skin(self, dt_next, dt_avg):
        """This rank's bound: may the next position update move an owned node half the skin
        from where it was at the last rebuild? Grain nodes, and with contact the blocks' too
        (global bodies never migrate, but their contact candidates are found at the
        rebuilds)."""
        s = self.store
        n0 = 0 if self.has_contact else s.nn_global
        return moves_half_skin(s.x, s.xref, s.v, self.f, s.m, s.bcf, s.bcv, n0, s.nn_own,
                               dt_next, dt_avg, 0.5 * self.skin)

    def refresh_reductions(self):
        """What the time step's reduction carries, for a state whose step has not ended
        through :meth:`next_dt` (after a restart or a rollback: v is already the next half
        step's, dt the next step's), each with a reduction of its own (collective)."""
        self.rebuild_next = global_any(self.comm, self._moves_half_skin(self.dt, 0.0))
        for e in self.minima:
            e.set_step_minimum(self.state, self.ctx,
                               global_min(self.comm, e.step_minimum(self.state, self.ctx)))

    def fail(self, msg):
        """Record a failed check in the state; all ranks stop together at the end of the
        step."""
        self.state.fail(msg)

    def advance_velocities(self, first=False):
        """Eq. 68 with the average of the two half steps; BCs, damping, kinetic energy."""
        s = self.store
        dt_avg = 0.5 * (self.dt_prev + self.dt)
        if self.bcs.releases:
            self.bcs.apply(self.store, self.t, self.t + self.dt)
        with self.timers.phase("integration"):
            advance_velocities(s.v, self.f, s.m, s.bcf, s.bcv, self.gamma, dt_avg, s.nn_own,
                               s.node_body, s.acc, self.kin[: s.nb_own], first, self.fc,
                               self.partner)

