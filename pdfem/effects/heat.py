"""The temperature field (scene table [heat]): capacity, sources, sub-cycled update.

With [heat] every node carries a temperature T [K] (initial value heat.initial), a lumped heat
capacity and, for the bodies' fixed-temperature nodes ([[thermal_bc]]), a held value. Each
step, after the forces (step 6 of the loop), the heat this step's sources produced is put on
the nodes and the temperatures advance:

    sources     dissipation heating and thermo-elastic coupling (element_heat, this module),
                contact conductance and friction heating (added by the contact effect)
    conduction  only with [conduction]; sub-cycled in n equal sub-steps when its stable step
                (times time.safety) is shorter than the mechanical step
    held nodes  reset to their temperature after each sub-step; the heat this takes is kept

The other heat effects (pdfem.effects.thermal, pdfem.effects.contact_heat) only switch parts
of this on; without [heat] none of them can exist (the scene check says so).

Energy (per body, summed like every other term), each source counted once, on the
mechanical side (pdfem.energy):
    thermal      sum C (T - T_initial), whatever put the heat there
    heat_paid    what the mechanics gave up as heat: beta x the plastic work and the friction
                 heating fraction x the frictional dissipation, from the mechanical
                 accumulators (the plastic and friction terms keep the whole dissipation)
    coupling     -3 alpha T_e p_e A_e summed over the elements, less its value at t = 0: the
                 coupled energy of thermo-elasticity. With thermal expansion (p = K (3 alpha
                 dT - eps_v)), the internal energy is e = U_elastic + c dT - 3 alpha T p per
                 unit volume, and the stress power on the total strain changes it; so the
                 thermo-elastic heat 3 alpha T d(pA) and the stress work on the thermal strain
                 are both paid by this term. One without the other creates energy: the scene
                 check refuses [thermoelastic] without [thermal_expansion] and the reverse.
                 An element of a Mie-Gruneisen material (eos_gamma > 0) has no thermal strain:
                 its thermal pressure is Gamma0 times its points' energy, and its compression
                 heats it adiabatically, dT = Gamma0 T d(eta); that heat is energy its stress
                 work already holds, so its term is minus the heat (pdfem.kernels.heat).
    heat_bc      what the held nodes took or gave
so thermal - heat_paid - heat_bc - (heat of thermo-elasticity) stays zero only when every
source has its mechanical counterpart; a source that has none shows in the balance error.
heat_sources (what the sources put on the nodes) and thermal_work (the stress work on the
thermal strain) are reported beside the balance, not in it.
"""

import math

import numpy as np

from pdfem.effects.base import Effect
from pdfem.effects.contact import CACC_FRIC
from pdfem.effects.thermal import fill_column
from pdfem.kernels.element_measures import q4_lumped_mass
from pdfem.kernels.heat import (
    H_CONDUCTED,
    H_FRICTION,
    H_PLASTIC,
    H_THERMOELASTIC,
    H_VISCOUS,
    NHEAT,
    accumulate_heat_sorted,
    advance_temperature,
    conduction_flows,
    conduction_stable_dt,
    coupling_state,
    element_areas,
    element_heat,
    element_thermal_state,
    element_to_nodes,
    hold_temperature,
    kirchhoff_pressure,
    thermal_energy,
)
from pdfem.kernels.integrate import body_sums
from pdfem.kernels.params import ALPHA, COND, CP, EOS_G, RHO, T_REF
from pdfem.store import BODY, ELEM, NODE, Field

# Columns of the per-body accumulator hacc
HACC_SRC = 0  # heat put in by the sources [J/m]
HACC_BC = 1  # heat put in by held (fixed-temperature) nodes [J/m]

# The mechanisms of the element heat (frame fields heat_<mechanism>) and their eheat columns
MECHANISM_COLUMN = {"plastic": H_PLASTIC, "viscous": H_VISCOUS,
                    "thermoelastic": H_THERMOELASTIC, "friction": H_FRICTION,
                    "conducted": H_CONDUCTED}
MECHANISMS = tuple(MECHANISM_COLUMN)

# Sub-steps of conduction per mechanical step are capped: more means a scene error
NSUB_MAX = 10000
# Effects whose element update needs the element temperatures (eth)
COUPLED = ("thermal_expansion", "temperature_dependence")

# Store fields of every heat run, and those of runs with COUPLED effects
FIELDS = (
    Field("T", NODE, (), np.float64),
    Field("tcap", NODE, (), np.float64),
    Field("tfix", NODE, (), np.int8),
    Field("tfixv", NODE, (), np.float64),
    Field("hacc", BODY, (2,), np.float64),
    Field("ewp_prev", ELEM, (), np.float64),
    Field("eheat", ELEM, (NHEAT,), np.float64),
)
# Store field of runs with viscous heating: the bulk-viscosity work at the last heat update
VISCOUS_FIELDS = (Field("ewq_prev", ELEM, (), np.float64),)
COUPLED_FIELDS = (
    Field("tprev", NODE, (), np.float64),
    Field("eth", ELEM, (3,), np.float64),
    Field("tau_prev", ELEM, (), np.float64),
    Field("area_ref", ELEM, (), np.float64),
)


class Heat(Effect):
    """Nodal temperatures, their capacity and their explicit update."""

    name = "heat"
    material_keys = ("specific_heat",)
    # The heat in the bodies, what paid for it and what left them; what the sources put on
    # the nodes and the stress work on the thermal strain are diagnostics
    energy = (("thermal", 1), ("heat_paid", -1), ("heat_bc", -1), ("coupling", 1),
              ("heat_sources", 0), ("thermal_work", 0))
    # Node temperatures, element means, and the heat each element received by mechanism
    frame_fields = {"temperature": ("node", ()), "element_temperature": ("elem", ()),
                    **{f"heat_{m}": ("elem", ()) for m in MECHANISMS}}
    frame_defaults = tuple(frame_fields)
    needs = "the [heat] table"
    halo_fields = ("T",)

    def __init__(self, table, scene):
        super().__init__(table, scene)
        self.t_init = float(table["initial"])
        # Element temperatures exist only for the effects that change the stress with them
        self.couple_elements = any(k in scene.resolved for k in COUPLED)
        self.extra_fields = (FIELDS + (COUPLED_FIELDS if self.couple_elements else ())
                             + (VISCOUS_FIELDS if "viscous_heating" in scene.resolved else ()))
        # Its options: the tables of the heat effects that switch on a part of it
        # (pdfem.effects.thermal), read here so that no effect configures another
        r = scene.resolved
        self.conduction = "conduction" in r
        self.beta = float(r["dissipation_heating"]["beta"]) if "dissipation_heating" in r else 0.0
        self.gamma = float(r["viscous_heating"]["fraction"]) if "viscous_heating" in r else 0.0
        self.thermoelastic = "thermoelastic" in r
        # The friction heating fraction ([friction_heating], an option of contact)
        self.friction_heat = (float(r["friction_heating"]["fraction"])
                              if "friction_heating" in r else 0.0)
        self.nsub = 1
        # Global conduction stable step of the last step's end (set with the time step)
        self.cond_dt = np.inf

    def setup(self, st, ctx):
        s = st.store
        fill_column(st, ctx, CP, "specific_heat")
        if self.conduction:
            fill_column(st, ctx, COND, "conductivity")
        if self.thermoelastic:
            fill_column(st, ctx, ALPHA, "expansion")
        ctx.mat_params[:, T_REF] = self.t_init
        if not ctx.restarted:
            # Initial temperatures; lumped capacity: the lumped mass with rho c in place of rho
            s.T[:] = self.t_init
            if self.couple_elements:
                s.tprev[:] = self.t_init
            cap_table = ctx.mat_params.copy()
            cap_table[:, RHO] = ctx.mat_params[:, RHO] * ctx.mat_params[:, CP]
            q4_lumped_mass(s.x, s.conn, s.emat, cap_table, 0, s.nelem, s.tcap)
            if self.couple_elements:
                element_areas(s.x, s.conn, 0, s.nelem, s.area_ref)
                coupling_state(s.x, s.conn, s.emat, ctx.mat_params, s.sig, s.mst, s.eth, 0,
                               s.nelem, s.tau_prev)
        self._hold_blocks(st, ctx)
        self.src = np.zeros(s.nnode)
        self.q = np.zeros(s.nnode)
        self.eh = np.zeros(s.nelem)

    def _hold_blocks(self, st, ctx):
        """Fixed temperatures of [[thermal_bc]] on block node sets (global bodies)."""
        s = st.store
        for bc in ctx.resolved.get("thermal_bc", []):
            nodes = ctx.blocks.nodes(bc["body"], bc["nodes"]) + s.nstart[
                ctx.blocks.index(bc["body"])]
            s.tfix[nodes] = 1
            s.tfixv[nodes] = bc["temperature"]

    def after_rebuild(self, st, ctx):
        """Scratch arrays follow the new store size (the fields themselves migrate)."""
        s = st.store
        self.src = np.zeros(s.nnode)
        self.q = np.zeros(s.nnode)
        self.eh = np.zeros(s.nelem)

    # ------------------------------------------------------------------ hooks of the step
    def before_elements(self, st, ctx):
        """Element temperatures and their increments since the last element update."""
        if not self.couple_elements:
            return
        s = st.store
        with ctx.timers.phase("heat"):
            element_thermal_state(s.T, s.tprev, s.conn, 0, s.ne_own, s.eth)
            s.tprev[: s.nn_own] = s.T[: s.nn_own]

    def add_contact_heat(self, order, active, nodes, weights, qa, qb, n_owned):
        """The contacts' heat of this step onto the owned nodes of their two sides, in the
        given (key) order (pdfem.kernels.heat.accumulate_heat_sorted): the contact effect's
        way into this effect's sources."""
        accumulate_heat_sorted(order, active, nodes, weights, qa, qb, n_owned, self.src)

    def heat(self, st, ctx):
        """Sources of this step onto the nodes, then the (sub-cycled) temperature update."""
        s = st.store
        dt = st.dt
        with ctx.timers.phase("heat"):
            # Element sources: dissipation, viscous heating, thermo-elastic coupling
            if self.beta > 0.0 or self.gamma > 0.0 or self.thermoelastic:
                none = np.empty(0)
                tau_prev, area_ref, eth = ((s.tau_prev, s.area_ref, s.eth) if self.thermoelastic
                                           else (none, none, np.empty((0, 3))))
                ewq, ewq_prev = (s.ewq, s.ewq_prev) if self.gamma > 0.0 else (none, none)
                element_heat(s.x, s.T, s.conn, s.emat, ctx.mat_params, s.sig, s.mst, eth,
                             area_ref, s.ewp, s.ewp_prev, ewq, ewq_prev, tau_prev, self.beta,
                             self.gamma, self.thermoelastic, 0, s.ne_own, self.eh, s.eheat)
                element_to_nodes(s.x, s.conn, 0, s.ne_own, self.eh, self.src)
            _body_node_sums(self.src, s.node_body, s.nn_own, s.hacc[:, HACC_SRC])
            # Conduction sub-steps (the sources enter with the first)
            nsub = self._substeps(st, ctx, dt) if self.conduction else 1
            h = dt / nsub
            for _ in range(nsub):
                if self.conduction:
                    bad = conduction_flows(s.x, s.T, s.conn, s.emat, ctx.mat_params, 0,
                                           s.ne_own, self.q)
                    if bad >= 0:
                        st.fail(f"check inverted element: element {s.elem_loc[bad]} of "
                                 f"body {s.elem_gid[bad]} is inverted (heat conduction)")
                advance_temperature(s.T, self.q, self.src, s.tcap, h, s.nn_own, ctx.partner)
                hold_temperature(s.T, s.tcap, s.tfix, s.tfixv, s.node_body, s.nn_own, s.hacc,
                                 HACC_BC)

    def step_minimum(self, st, ctx):
        """The local conduction stable step (with [conduction]): its global minimum comes back
        with the time step's reduction and sets the next step's sub-steps."""
        if not self.conduction:
            return np.inf
        s = st.store
        return conduction_stable_dt(s.x, s.conn, s.emat, ctx.mat_params, 0, s.ne_own)

    def set_step_minimum(self, st, ctx, value):
        self.cond_dt = value

    def _substeps(self, st, ctx, dt):
        """Equal conduction sub-steps within dt, from the global conduction limit of the
        positions at the end of the last step (set with the time step)."""
        lim = self.cond_dt * st.safety
        nsub = 1 if lim >= dt else math.ceil(dt / lim)
        if nsub > NSUB_MAX:
            st.fail(f"check conduction sub-steps: heat conduction needs {nsub} sub-steps of "
                     f"{lim:.3e} s per step of {dt:.3e} s (more than {NSUB_MAX})")
            nsub = NSUB_MAX
        self.nsub = nsub
        return nsub

    def frame_values(self, st, ctx, name, nodes, elems):
        """Temperatures of nodes, element means, element heat of one mechanism."""
        s = st.store
        if name == "temperature":
            return s.T[nodes]
        if name == "element_temperature":
            return s.T[s.conn[elems]].mean(axis=1)
        return s.eheat[elems, MECHANISM_COLUMN[name.removeprefix("heat_")]]

    def energy_terms(self, st, ctx, out):
        s = st.store
        nb, ne = s.nb_own, s.ne_own
        e = np.empty(nb)
        thermal_energy(s.T, self.t_init, s.tcap, s.node_body, s.nn_own, e)
        out["thermal"] = e
        out["heat_sources"] = s.hacc[:nb, HACC_SRC].copy()
        out["heat_bc"] = s.hacc[:nb, HACC_BC].copy()
        # The dissipation that became heat, from the mechanical accumulators
        paid = np.zeros(nb)
        if self.beta > 0.0:
            body_sums(self.beta * s.ewp[:ne], s.estart[:nb], s.ne[:nb], paid)
        if self.gamma > 0.0:
            viscous = np.empty(nb)
            body_sums(s.ewq[:ne], s.estart[:nb], s.ne[:nb], viscous)
            paid += self.gamma * viscous
        if self.friction_heat > 0.0:
            # The contacts' frictional dissipation (friction heating needs [contact])
            paid += self.friction_heat * s.contact_acc[:nb, CACC_FRIC]
        out["heat_paid"] = paid
        if self.couple_elements:
            w = np.empty(nb)
            body_sums(s.eth[:ne, 2], s.estart[:nb], s.ne[:nb], w)
            out["thermal_work"] = w
        if self.thermoelastic:
            # -3 alpha T_e p_e A_e of the present state; minus the heat a Mie-Gruneisen
            # material's compression gave, which its stress work already holds
            tau = np.empty(ne)
            kirchhoff_pressure(s.x, s.conn, s.sig, 0, ne, tau)
            te = s.T[s.conn[:ne]].mean(axis=1)
            eos = ctx.mat_params[s.emat[:ne], EOS_G] > 0.0
            ce = np.where(eos, -s.eheat[:ne, H_THERMOELASTIC],
                          -3.0 * ctx.mat_params[s.emat[:ne], ALPHA] * te * tau)
            c = np.empty(nb)
            body_sums(ce, s.estart[:nb], s.ne[:nb], c)
            out["coupling"] = c



def _body_node_sums(val, node_body, n1, out):
    """out[b] += sum of val over the owned nodes of body b (node order, via bincount)."""
    if n1:
        out += np.bincount(node_body[:n1], weights=val[:n1], minlength=out.shape[0])[
            : out.shape[0]]
