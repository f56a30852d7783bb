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

from partition import CellGrid, needs_rebalance, partition
from pdfem import build
from pdfem.drive import Drives
from pdfem.effects import active_effects
from pdfem.effects.base import hook_table
from pdfem.effects.contact import check_contact_scene
from pdfem.energy import energy_floor, initial_strain_work
from pdfem.errors import InputError, SimulationError
from pdfem.guards import Guards, contact_stiffness_cap
from pdfem.kernels.checks import first_nonfinite
from pdfem.kernels.element import q4_forces_2x2
from pdfem.kernels.element_1pt import q4_forces_1pt
from pdfem.kernels.element_measures import q4_lumped_mass
from pdfem.kernels.integrate import NACC, advance_positions, advance_velocities, moves_half_skin
from pdfem.kernels.material import material_initial_state
from pdfem.kernels.stable import q4_stable_dt
from pdfem.memory import trim
from pdfem.mesh.quality import corner_jacobians
from pdfem.parallel.exchange import cell_reach, owned_grain_cells, rebuild
from pdfem.parallel.mpi import (
    allgather_objects,
    array_max,
    array_sum,
    global_any,
    global_min,
    global_sum_exact,
)
from pdfem.store import NODE, Batch, Field, Store, core_fields
from pdfem.timers import Timers

# A restart's contact forces of the last step, carried with the nodes to their owners
RESTART_FC = Field("restart_contact_force", NODE, (2,), np.float64)

# Element temperatures of a run without thermo-mechanical coupling (the kernels skip them)
NO_ETH = np.zeros((0, 3))


class Simulation:
    """One run of a scene on a communicator: setup, :meth:`step`, :meth:`run`."""

    def __init__(self, scene, comm, init_state=None, restart=None):
        r = scene.resolved
        self.scene, self.comm, self.resolved = scene, comm, r
        self.timers = Timers()
        self._fail_msg = ""
        check_contact_scene(r)
        self.effects = active_effects(r, scene)
        self.effect_names = [e.name for e in self.effects]
        # The temperature field's owner (None without [heat]): the handle the contact heat
        # and the diagnostics use
        self.heat = next((e for e in self.effects if e.name == "heat"), None)
        damping = [e for e in self.effects if e.name == "damping"]
        self.gamma = damping[0].gamma if damping else 0.0
        self.mat_params = build.material_table(r["materials"])
        nst = build.check_materials(r["materials"], self.mat_params)
        self.mat_ids = {name: i for i, name in enumerate(r["materials"])}
        el = r["element"]
        self.nip = 1 if el["rule"] == "1pt" else 4
        self.element_kernel = q4_forces_1pt if el["rule"] == "1pt" else q4_forces_2x2
        self.hg_coef = float(el["hourglass"]) if el["rule"] == "1pt" else 0.0
        self.fields = core_fields(self.nip, nst, NACC)
        for eff in self.effects:
            self.fields += [f for f in eff.extra_fields if f not in self.fields]
        self.halo_fields = ["x", "v"] + [n for e in self.effects for n in e.halo_fields]
        # Element temperatures exist (store field eth) when heat couples into the elements
        self.coupled = any(f.name == "eth" for f in self.fields)
        # Without it the 1-point kernel takes None (compiled without the thermal branches)
        self.no_eth = None if el["rule"] == "1pt" else NO_ETH
        dom, tm = r["domain"], r["time"]
        self.box = tuple(dom["box"])
        self.grid = CellGrid(self.box, dom["cell_size"])
        self.skin = dom["skin"]
        self.safety, self.t_end = tm["safety"], tm["end"]
        self.dt_max, self.dt_min, self.max_steps = tm["dt_max"], tm["dt_min"], tm["max_steps"]
        self.layout = build.Layout(scene.grains["center"].shape[0], el["level"],
                                   r.get("blocks", []))
        self.has_contact = "contact" in r
        self.rebalances = 0
        self.restarted = restart is not None
        # Stop and checkpoint requests: local flags, shared by the reduction of next_dt
        self.stop_requested = self.checkpoint_requested = False
        self.local_stop = self.local_ckpt = 0.0
        self._build_initial(scene, init_state)
        self.checkpoint = None
        if restart is not None:
            self._build_restart(restart)
        for eff in self.effects:
            eff.setup(self)
        # The effects that use each step hook, listed once
        self.hooks = hook_table(self.effects)
        self.minima = self.hooks["step_minimum"]
        self.drives = Drives(self)
        self.guards = Guards(self)
        self._cap_contact(restart)
        self.energy_floor = energy_floor(self)
        # The set-up's temporaries are freed: give their pages back to the OS
        trim()
        self._fail_msg = ""
        self.t, self.nstep = 0.0, 0
        # No step has a length before the first next_dt: set-up evaluates forces at dt = 0
        self.dt = self.dt_prev = 0.0
        self.du = np.zeros_like(self.store.v)
        self._fresh_arrays()
        if restart is not None:
            # Continue exactly where the checkpoint stopped
            st = self.checkpoint.state
            self.t, self.nstep, self.dt, self.dt_prev = st["t"], st["nstep"], st["dt"], \
                st["dt_prev"]
            # A time step the remedy halved stays halved unless the scene asks for less
            self.safety = min(self.safety, st.get("safety", self.safety))
            self.guards.retries_left = min(self.guards.retries,
                                           st.get("dt_retries_left", self.guards.retries))
            self.refresh_reductions()
            return
        # Forces at t = 0 and the first half step; energy accumulators from the t = 0 state
        initial_strain_work(self)
        self.compute_forces()
        for eff in self.hooks["start_work"]:
            eff.start_work(self)
        self.dt_prev = 0.0
        self.dt = self.next_dt()
        self.advance_velocities(first=True)

    # ------------------------------------------------------------------ setup
    def _build_initial(self, scene, init_state):
        """Mesh the grains this rank owns at t=0 and all blocks; distribute; lumped mass."""
        comm, r = self.comm, self.resolved
        g = scene.grains
        ng = g["center"].shape[0]
        cells = self.grid.cell_of(g["center"])
        weights = np.bincount(cells, minlength=self.grid.ncell).astype(float)
        self.owner = partition(r["domain"]["partition"], weights, self.grid.nx, self.grid.ny,
                               comm.size)
        mine = np.nonzero(self.owner[cells] == comm.rank)[0]
        level = r["element"]["level"]
        grains = build.grain_batch(self.fields, self.nip, self.fields_nst(), level,
                                   mine.astype(np.int64), g["center"][mine], g["axes"][mine],
                                   g["angle"][mine], g["velocity"][mine], g["material"][mine])
        if "nodes" in g:
            # A prepared bed: the grain meshes as the preparation left them
            grains.a["x"] = g["nodes"][mine].reshape(-1, 2).copy()
            grains.a["v"] = g["node_v"][mine].reshape(-1, 2).copy()
        blocks = r.get("blocks", [])
        bbatch, bsets = build.block_batch(self.fields, self.nip, self.fields_nst(), blocks, ng,
                                          self.mat_ids)
        self.block_names, self.block_sets = [b["name"] for b in blocks], bsets
        self.nglobal = len(blocks)
        first = np.concatenate(([0], np.cumsum(bbatch.a["nn"])[:-1])).astype(np.int64)
        build.apply_bcs(bbatch, r.get("bc", []), self.box, [b["name"] for b in blocks], bsets,
                        first)
        build.apply_bcs(grains, [b for b in r.get("bc", []) if "wall" in b], self.box, [], [],
                        [])
        batch = Batch.concat(self.fields, [bbatch, grains])
        material_initial_state(batch.a["mst"], batch.a["emat"], self.mat_params)
        if "elem_sig" in g:
            self._bed_stress(batch, g, mine, int(bbatch.a["ne"].sum()))
        store = Store(self.fields, batch, batch.nbody)
        q4_lumped_mass(store.x, store.conn, store.emat, self.mat_params, 0, store.ne_own,
                       store.m)
        if init_state is not None:
            init_state(self, store)
        with self.timers.phase("migration"):
            self.store, self.halo = self.rebuild(store)

    def _build_restart(self, path):
        """Replace the initial bodies by a checkpoint's: every rank reads the global bodies
        and a block of grains, and the rebuild moves each grain to the owner of its cell,
        with the contact forces of its nodes riding along, and makes the ghosts."""
        from pdfem.io.checkpoint import read_checkpoint

        ck = read_checkpoint(path, self.fields, self.comm)
        self.checkpoint = ck
        _same_scene(path, ck.scene_text, self.scene.to_toml_string())
        fields = self.fields + ([RESTART_FC] if ck.contact_force is not None else [])
        if ck.contact_force is not None:
            ck.batch.a[RESTART_FC.name] = ck.contact_force
        store = Store(fields, Batch(fields, ck.batch.a), ck.batch.nbody)
        # The partition of the checkpoint's grains: cell weights summed over the ranks
        cells = owned_grain_cells(store, self.grid, self.nglobal)
        weights = np.bincount(cells, minlength=self.grid.ncell).astype(float)
        array_sum(self.comm, weights)
        self.owner = partition(self.resolved["domain"]["partition"], weights, self.grid.nx,
                               self.grid.ny, self.comm.size)
        with self.timers.phase("migration"):
            store, self.halo = self.rebuild(store)
        if ck.contact_force is not None:
            # The owned nodes' forces for the first frame; the store without them
            ck.contact_force = getattr(store, RESTART_FC.name)[: store.nn_own].copy()
            store = Store(self.fields, Batch(self.fields, {f.name: getattr(store, f.name)
                                                           for f in self.fields}),
                          store.nb_own)
        self.store = store

    def _cap_contact(self, restart):
        """The cap_contact remedy (pdfem.guards); a restart reuses the checkpoint's cap."""
        self.contact_cap = None
        if self.resolved["guards"]["cap_contact"] == "off":
            return
        contact = [e for e in self.effects if e.name == "contact"][0]
        saved = self.checkpoint.state.get("contact_cap") if restart is not None else None
        self.contact_cap, line = contact_stiffness_cap(self, contact, saved)
        if line:
            self.guards.actions.append(line)

    def _bed_stress(self, batch, g, mine, e0):
        """Stresses and material state of a prepared bed's grains (elements after e0)."""
        sig, mst = g["elem_sig"], g["elem_mst"]
        nip, nst = batch.a["sig"].shape[1], batch.a["mst"].shape[2]
        if sig.shape[2] != nip or mst.shape[3] != nst:
            raise InputError(f"grains_file: the bed file holds {sig.shape[2]} integration "
                             f"point(s) and {mst.shape[3]} state variable(s) per element; this "
                             f"scene has {nip} and {nst} (element.rule and the material models "
                             "must be the preparation's)")
        batch.a["sig"][e0:] = sig[mine].reshape(-1, nip, 4)
        batch.a["mst"][e0:] = mst[mine].reshape(-1, nip, nst)

    def fields_nst(self):
        """Number of material state variables per integration point."""
        return [f for f in self.fields if f.name == "mst"][0].shape[1]

    # ------------------------------------------------------------------ the step
    def step(self):
        """Advance one time step (see the module docstring for the order)."""
        s = self.store
        # 1. positions to t + dt
        with self.timers.phase("integration"):
            advance_positions(s.x, s.v, self.dt, s.nn_own, self.du)
            self.t += self.dt
            self.nstep += 1
        # 2. neighbourhood: rebuild or halo refresh
        self.neighbourhood()
        # 3-5. internal, contact and body forces
        self.compute_forces()
        # 6. heat
        for eff in self.hooks["heat"]:
            eff.heat(self)
        # 7. next dt, velocities, diagnostics
        self.dt_prev = self.dt
        self.dt = self.next_dt()
        self.advance_velocities()

    def neighbourhood(self):
        """Rebuild ghosts and migrate when the last step's reduction said that this step's
        position update may move a node half the skin (:meth:`next_dt`)."""
        s = self.store
        if self.rebuild_next:
            with self.timers.phase("migration"):
                self._rebalance()
                self.store, self.halo = self.rebuild(s)
            s = self.store
            self._fresh_arrays()
            for eff in self.effects:
                eff.after_rebuild(self)
        else:
            with self.timers.phase("halo"):
                self.halo.refresh([getattr(s, n) for n in self.halo_fields])
        # Step increments of ghosts are derived exactly as their owners computed them
        self.du = self.dt * s.v

    def _fresh_arrays(self):
        """The per-step arrays sized to the store, zeroed: the one place they are made (set-up,
        a rebuild, a rollback): forces f, contact forces fc, kinetic energies kin."""
        s = self.store
        self.f = np.zeros_like(s.v)
        self.fc = self.contact_force_array()
        self.kin = np.zeros(s.nbody)

    def restore(self, snap):
        """Back to a last good state of the guards (:class:`pdfem.guards.Snapshot`)
        (collective): its bodies rebuilt on its partition, its time and steps, the per-step
        arrays fresh, the effects told, the reductions redone."""
        self.owner = snap.owner.copy()
        with self.timers.phase("migration"):
            self.store, self.halo = self.rebuild(Store(self.fields, snap.batch, snap.nb_own))
        self.nstep, self.t, self.dt, self.dt_prev = snap.nstep, snap.t, snap.dt, snap.dt_prev
        self.du = np.zeros_like(self.store.v)
        self._fresh_arrays()
        self._fail_msg = ""
        self.stop_requested = False
        for eff in self.effects:
            eff.after_rebuild(self)
        self.refresh_reductions()

    def halve_step(self):
        """The time-step remedy: time step and time.safety halved; returns the old safety."""
        old = self.safety
        self.safety *= 0.5
        self.dt *= 0.5
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
        the cell reach of its grains (collective); returns (store, halo). The reach is kept
        for the contact candidates (:func:`pdfem.parallel.exchange.cell_reach`)."""
        self.reach = cell_reach(self.comm, store, self.grid, self.nglobal, self.skin)
        return rebuild(self.comm, store, self.grid, self.owner, self.nglobal, self.reach)

    def _rebalance(self):
        """At a rebuild: new cell owners when the element-count load of the ranks is more
        than domain.rebalance times its mean. Every rank computes the same exact integer
        weights, so all agree; results do not depend on ownership (bit-identical)."""
        threshold = self.resolved["domain"]["rebalance"]
        if threshold <= 0.0 or self.comm.size == 1:
            return
        s = self.store
        own = np.arange(self.nglobal, s.nb_own)
        cells = owned_grain_cells(s, self.grid, self.nglobal)
        w = np.bincount(cells, weights=s.ne[own], minlength=self.grid.ncell).astype(np.int64)
        w = global_sum_exact(self.comm, w)
        weights = w.astype(float)
        if needs_rebalance(weights, self.owner, self.comm.size, threshold):
            self.owner = partition(self.resolved["domain"]["partition"], weights, self.grid.nx,
                                   self.grid.ny, self.comm.size)
            self.rebalances += 1

    def compute_forces(self):
        """Residual force f = P - I on owned nodes: elements, contact, body forces."""
        s = self.store
        self.f[:] = 0.0
        for eff in self.hooks["before_elements"]:
            eff.before_elements(self)
        with self.timers.phase("elements"):
            bad = self.element_kernel(s.x, self.du, s.conn, s.emat, self.mat_params, s.sig,
                                      s.mst, s.hgq, self.hg_coef, 0, s.ne_own, self.f, s.ewint,
                                      s.ewp, s.eth if self.coupled else self.no_eth)
        if bad >= 0:
            self.fail(self._element_failure(bad))
        if self.has_contact:
            # The contacts' forces go to fc (their work is accounted per body), then to f
            self.fc[:] = 0.0
            for eff in self.hooks["contact_forces"]:
                eff.contact_forces(self)
            self.f += self.fc
        for eff in self.hooks["body_force"]:
            eff.body_force(self)
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
        dt_loc = q4_stable_dt(s.x, s.conn, s.emat, self.mat_params, 0, s.ne_own)
        limiter = "the element wave speed"
        for eff in self.hooks["stable_dt"]:
            d = eff.stable_dt(self)
            if d < dt_loc:
                dt_loc, limiter = d, eff
        if not dt_loc > self.dt_min and not self._fail_msg:
            if not isinstance(limiter, str):
                limiter = limiter.dt_limiter(self, dt_loc)
            self.fail(f"check time step: the stable dt {dt_loc:.3e} s (limited by {limiter}) is "
                      f"below time.dt_min {self.dt_min:.3e} s")
        # Whether the next step's position update may move a grain node half the skin: the
        # next step is at most this rank's limit, so a bound decides before the reduction
        dt_up = min(self.safety * dt_loc, self.dt_max)
        ahead = self._moves_half_skin(dt_up, 0.5 * (self.dt_prev + dt_up))
        # One reduction: the step, the fail, stop, checkpoint and rebuild flags, the effects'
        # minima
        red = np.array([-dt_loc, 1.0 if self._fail_msg else 0.0, self.local_stop,
                        self.local_ckpt, float(ahead)]
                       + [-e.step_minimum(self) for e in self.minima])
        red = array_max(self.comm, red)
        self.rebuild_next = bool(red[4] > 0)
        for e, value in zip(self.minima, red[5:], strict=True):
            e.set_step_minimum(self, -value)
        self.stop_requested = self.stop_requested or red[2] > 0
        self.checkpoint_requested = self.checkpoint_requested or red[3] > 0
        self.local_ckpt = 0.0
        if red[1] > 0:
            msgs = [m for m in allgather_objects(self.comm, self._fail_msg) if m]
            raise SimulationError(f"step {self.nstep}, t={self.t:.6e} s: {msgs[0]}")
        dt_stable = -red[0]
        # No clipping to output times: an abrupt change of dt would spoil the energy identity
        return min(self.safety * dt_stable, self.dt_max)

    def _moves_half_skin(self, dt_next, dt_avg):
        """This rank's bound: may the next position update move an owned grain node half the
        skin from where it was at the last rebuild (global bodies never migrate)?"""
        s = self.store
        return moves_half_skin(s.x, s.xref, s.v, self.f, s.m, s.bcf, s.bcv, s.nn_global,
                               s.nn_own, dt_next, dt_avg, 0.5 * self.skin)

    def refresh_reductions(self):
        """What the time step's reduction carries, for a state whose step has not ended
        through :meth:`next_dt` (after a restart or a rollback: v is already the next half
        step's, dt the next step's), each with a reduction of its own (collective)."""
        self.rebuild_next = global_any(self.comm, self._moves_half_skin(self.dt, 0.0))
        for e in self.minima:
            e.set_step_minimum(self, global_min(self.comm, e.step_minimum(self)))

    def contact_force_array(self):
        """Zeroed contact forces of the store's nodes; shape (0, 2) without contact."""
        return np.zeros_like(self.store.v) if self.has_contact else np.zeros((0, 2))

    def fail(self, msg):
        """Record a failed check; all ranks stop together at the end of the step."""
        if not self._fail_msg:
            self._fail_msg = msg

    def advance_velocities(self, first=False):
        """Eq. 68 with the average of the two half steps; BCs, damping, kinetic energy."""
        s = self.store
        dt_avg = 0.5 * (self.dt_prev + self.dt)
        if len(self.drives):
            self.drives.apply(self, self.t, self.t + self.dt)
        with self.timers.phase("integration"):
            advance_velocities(s.v, self.f, s.m, s.bcf, s.bcv, self.gamma, dt_avg, s.nn_own,
                               s.node_body, s.acc, self.kin[: s.nb_own], first, self.fc)


def _same_scene(path, saved, given):
    """A restart must run the checkpoint's scene; only [output], [guards] and the time keys
    end, safety, dt_min and max_steps may change."""
    import tomllib

    a, b = tomllib.loads(saved), tomllib.loads(given)
    for d in (a, b):
        d.pop("output", None)
        d.pop("guards", None)
        for key in ("end", "safety", "dt_min", "max_steps"):
            d.get("time", {}).pop(key, None)
    if a == b:
        return
    for key in sorted(set(a) | set(b)):
        if a.get(key) != b.get(key):
            raise InputError(f"--restart: {path} was written for a different scene ([{key}] "
                             "differs; only [output], [guards], time.end, time.safety, "
                             "time.dt_min and time.max_steps may change)")
