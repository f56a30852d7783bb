"""Contact between bodies (report sec. 5): the overlap law, found on the cell grid.

The candidates (element pairs and element-wall pairs, in contact-key order) come from
:mod:`pdfem.effects.contact_candidates`. Every step one kernel pass
(pdfem.kernels.contact.contact_pass) runs down them: it keeps those whose boxes overlap now
(or reach behind the wall), clips them, evaluates the law and writes the contacts that touch
in key order.

Bit-for-bit reproducibility: each pair is evaluated in canonical orientation (lower global key
first) by every rank that owns one side; forces are added to owned nodes in the order of the
contact keys (gid_a, elem_a, gid_b, elem_b). A block's nodes receive the forces of contacts
computed on every rank, so those contributions are gathered and every rank adds all of them
in key order. Contact history (the elastic shear displacement) is kept per key, sorted, and
travels with a grain when it migrates.
"""

import numpy as np

from pdfem.build import joint_masses
from pdfem.effects.base import Effect
from pdfem.effects.contact_candidates import Candidates, lexorder
from pdfem.effects.contact_cap import contact_stiffness_cap
from pdfem.errors import InputError
from pdfem.kernels import contact_law as L
from pdfem.kernels.contact import (
    C_ACTIVE,
    NNOD,
    NRES,
    R_DELTA,
    R_DISS,
    R_WIDTH,
    contact_pass,
)
from pdfem.kernels.contact_step import (
    accumulate_sorted,
    contact_bookkeeping,
    contact_dt_min,
    entry_dt_min,
    first_guarded,
    max_speed,
)
from pdfem.kernels.grain_depth import element_depths
from pdfem.kernels.heat import (
    accumulate_element_heat_sorted,
    contact_heat,
)
from pdfem.kernels.integrate import ACC_CWORK
from pdfem.parallel.mpi import allgather_rows
from pdfem.store import BODY, Field

# contact.law: the overlap measure of the normal law (contact_law.P_LAW)
LAWS = {"area": L.LAW_AREA, "potential": L.LAW_POTENTIAL}

# Beyond RCAP * delta_max the hardening law continues along its tangent (see contact_law)
RCAP = 0.95
# A step may close a gap by at most this fraction of delta_max (two bodies each moving at the
# fastest node speed): the overlap law must see a contact before it is deep
APPROACH = 0.1
# No per-candidate law rows or history (contact_pass: the materials' law, the sorted history)
NO_ROWS = np.zeros(0, np.int64)
NO_HISTORY = np.zeros(0)
# No force array: the pass leaves the forces to _apply (blocks' rows are gathered first)
NO_FORCES = np.zeros((0, 2))
# Columns of the contacts' per-body accumulator (store field contact_acc): the energy
# dissipated by friction and by the normal damping of the contacts the body is side A of [J/m]
CACC_FRIC = 0
CACC_DAMP = 1
CONTACT_ACC = Field("contact_acc", BODY, (2,), np.float64)
# Outward normals of the domain walls (pointing into the domain) and their box coordinate
WALL_SIDES = {"left": ((1.0, 0.0), 0), "bottom": ((0.0, 1.0), 1), "right": ((-1.0, 0.0), 2),
              "top": ((0.0, -1.0), 3)}


class Contact(Effect):
    """The report's frictional, no-tension, hardening contact (scene tables [contact], [walls])."""

    name = "contact"
    # Stored energy, friction and normal-damping losses; contact_loss, what the contacts
    # absorbed beyond those three, is a diagnostic (pdfem.energy)
    energy = (("contact", 1), ("friction", 1), ("contact_damping", 1), ("contact_loss", 0))
    # The contacts' nodal forces per frame; every contact of a frame's step (pdfem.io.contacts)
    frame_fields = {"contact_force": ("node", (2,))}
    extra_fields = (CONTACT_ACC,)
    outputs = ("contacts",)
    needs = "the [contact] table"

    def __init__(self, table, scene):
        super().__init__(table, scene)
        names = list(scene.materials)
        nmat = len(names)
        self.law = np.zeros((nmat, nmat, L.NPAR))
        # Per material pair law parameters: the [contact] values, overridden per pair
        for i, a in enumerate(names):
            for j, b in enumerate(names):
                over = table["pairs"].get(f"{a}:{b}", table["pairs"].get(f"{b}:{a}", {}))
                row = self.law[i, j]
                row[L.P_KN0] = over.get("kn0", table["kn0"])
                row[L.P_DMAX] = over.get("delta_max", table["delta_max"])
                row[L.P_KS] = over.get("ks", table["ks"])
                row[L.P_MU] = over.get("friction", table["friction"])
                row[L.P_RCAP] = RCAP
                row[L.P_ZETA] = over.get("damping", table["damping"])
                row[L.P_LAW] = LAWS[table["law"]]
        self.zeta_max = float(self.law[:, :, L.P_ZETA].max())
        self.delta_max = float(self.law[:, :, L.P_DMAX].max())
        self.delta_min = float(self.law[:, :, L.P_DMAX].min())
        self.kn0_max = float(self.law[:, :, L.P_KN0].max())
        # Domain walls: the contact law of the [contact] table with the wall friction
        box = scene.resolved["domain"]["box"]
        walls = scene.resolved.get("walls", {})
        self.walls = []
        for side, (normal, coord) in WALL_SIDES.items():
            kind = walls.get(side, "none")
            if kind == "none":
                continue
            p0 = np.array([box[0], box[1]]) if coord < 2 else np.array([box[2], box[3]])
            mu = walls["friction"] if kind == "frictional" else 0.0
            self.walls.append((p0, np.array(normal), mu))
        self._wall_p0 = np.array([w[0] for w in self.walls]).reshape(-1, 2)
        self._wall_n = np.array([w[1] for w in self.walls]).reshape(-1, 2)
        self._wall_mu = np.array([w[2] for w in self.walls], float)
        self.friction = bool(self.law[:, :, L.P_MU].max() > 0 or any(w[2] > 0 for w in self.walls))
        # Heat across contacts: its options [contact_conductance] and [friction_heating]
        r = scene.resolved
        self.heat_h = float(r["contact_conductance"]["h"]) if "contact_conductance" in r else 0.0
        self.heat_fraction = (float(r["friction_heating"]["fraction"])
                              if "friction_heating" in r else 0.0)
        # Candidate element pairs: found at each rebuild, merged with the blocks' each step;
        # with the potential law also the pairs of a boundary element and any element of the
        # other body (grain_depth)
        self.deep = bool((self.law[:, :, L.P_LAW] == L.LAW_POTENTIAL).any())
        self.detect = Candidates(self._wall_p0, self._wall_n, self.deep)
        # The potential law's values at the elements' corners and centroids (after_rebuild)
        self.depth = (np.zeros((0, 4)), np.zeros(0))
        self._rows = 0
        self._outputs(1024)
        self._boxes = np.empty((0, 4))
        # The contacts of the last evaluation (active flags, keys, nodes, results, ...; None
        # before the first), for the step limit, the diagnostics and the per-contact output
        self.last = None
        # Stored contact energy per local body at the last evaluation [J/m]
        self.stored = np.zeros(0)
        self._q = None

    def setup(self, st, ctx):
        self.after_rebuild(st, ctx)
        # The cap_contact remedy: laws no stiffer than the elements' initial stable step allows
        # (pdfem.effects.contact_cap); a restart takes the cap its run started with
        self.stiffness_cap = None
        if ctx.resolved["guards"]["cap_contact"] != "off":
            self.stiffness_cap, line = contact_stiffness_cap(st, ctx, self,
                                                             ctx.saved.get("contact_cap"))
            if line:
                self.remedies.append(line)

    # ------------------------------------------------------------------ detection
    def after_rebuild(self, st, ctx):
        """The candidates of the rebuilt store (pdfem.effects.contact_candidates) and the
        potential law's field over its bodies (pdfem.kernels.grain_depth)."""
        s = st.store
        edep, eapex = np.zeros((s.nelem, 4)), np.zeros(s.nelem)
        # The masses the contacts see: a tied pair of block nodes moves as one
        self.mass = joint_masses(s.m, ctx.partner)
        if self.deep:
            element_depths(s.conn, s.ebnd, s.elen, s.estart, s.ne, s.nstart, s.nn, edep, eapex)
        self.depth = (edep, eapex)
        self.detect.rebuild(st, ctx)

    @property
    def gpairs(self):
        """Candidate grain pairs of the last rebuild (local body indices)."""
        return self.detect.gpairs

    # ------------------------------------------------------------------ forces
    def contact_forces(self, st, ctx):
        """Evaluate every contact this rank needs and add the forces in key order."""
        with ctx.timers.phase("contact_detection"):
            cand = self.detect.step(st, ctx)
        with ctx.timers.phase("contact_forces"):
            self._evaluate(st, ctx, cand)

    def _outputs(self, rows):
        """Output arrays of the contact pass with room for rows contacts (kept between steps:
        no allocation per step)."""
        if self._rows < rows:
            self._rows = rows
            self._buf = (np.empty(rows, np.int8), np.empty((rows, 4), np.int64),
                         np.empty((rows, 2), np.int64), np.empty((rows, NNOD), np.int64),
                         np.empty((rows, NNOD)), np.empty((rows, NNOD, 2)), np.empty(rows),
                         np.empty((rows, NRES)))
        return self._buf

    def _bbox(self, n):
        """Scratch for the n elements' boxes (kept between steps)."""
        if self._boxes.shape[0] != n:
            self._boxes = np.empty((n, 4))
        return self._boxes

    def _evaluate(self, st, ctx, cand):
        s = st.store
        dt = st.dt
        # Without blocks every contact is local and in key order: the pass adds the forces (all
        # of them, also those whose rows did not fit: a second call only writes the rows)
        added = ctx.nglobal == 0
        forces = st.fc if added else NO_FORCES
        while True:
            out = self._outputs(self._rows)
            n, _, nev = contact_pass(s.x, st.du, self.mass, s.conn, s.ebnd, s.elem_gid, s.elem_loc,
                                       s.elen, *self.depth, s.emat,
                                       self.law.reshape(-1, L.NPAR),
                                       self.law.shape[0], NO_ROWS, self._wall_p0, self._wall_n,
                                       self._wall_mu, cand, s.hkey, s.hval, NO_HISTORY, False,
                                       False, dt, self._bbox(s.nelem), forces, s.nn_own,
                                       *out, ctx.grid.period)
            if n <= self._rows:
                break
            self._outputs(n + n // 4 + 64)
            forces = NO_FORCES
        active, keys, elems, nodes, weights, fnod, us_out, res = (o[:n] for o in out)
        self._check(st, ctx, keys, active, res)
        self._apply(st, ctx, keys, active, nodes, weights, fnod, res, elems, not added)
        self._bookkeeping(st, ctx, keys, active, us_out, res, elems)
        self.last = {"active": active, "nodes": nodes, "res": res, "fnod": fnod, "keys": keys,
                      "candidates": cand.shape[0], "evaluated": nev, "elems": elems, "dt": dt,
                      "q": self._q}

    def _check(self, st, ctx, keys, active, res):
        """Guards: a degenerate overlap, or a mean overlap delta = area / L (the law's) beyond
        delta_max; the first in key order is named."""
        p = first_guarded(active, res, self.delta_max)
        if p >= 0:
            k = keys[p]
            what = (f"deeper than contact.delta_max (delta = {res[p, R_DELTA]:.3e} m)"
                    if active[p] == C_ACTIVE else "degenerate (one element inside the other)")
            other = f"wall {-1 - k[2]}" if k[2] < 0 else f"body {k[2]} element {k[3]}"
            st.fail(f"check contact overlap: the contact between body {k[0]} element {k[1]} "
                     f"and {other} is {what}")

    def _apply(self, st, ctx, keys, active, nodes, weights, fnod, res, elems, forces):
        """Add forces (unless the pass did: forces False) and contact heat to owned nodes in
        key order (the rows' order); block-side rows are gathered from all ranks."""
        s = st.store
        # Heat of each contact on its two sides (this step, over st.dt), its friction part,
        # and the elements of the two sides (-1: a wall)
        heat = (self.heat_h > 0.0 or self.heat_fraction > 0.0) and st.dt > 0.0
        q = None
        if heat:
            q = np.zeros((active.shape[0], 4))
            contact_heat(active, nodes, weights, res, s.T, self.heat_h, self.heat_fraction,
                         st.dt, R_WIDTH, R_DISS, q[:, 0], q[:, 1], q[:, 2], q[:, 3])
        # Kept for the per-contact output (pdfem.io.contacts)
        self._q = q
        order = np.arange(active.shape[0])
        # No blocks: every contact is local, already in key order
        if ctx.nglobal == 0:
            self._add(st, ctx, order, active, nodes, weights, fnod, q, elems, forces)
            return
        isg = s.isglobal[s.elem_body]
        mixed = (elems[:, 1] >= 0) & (isg[elems[:, 0]] != isg[elems[:, 1]])
        local_nodes = nodes.copy()
        # Canonical orientation puts the grain (lower gid) first: its block side is gathered
        local_nodes[mixed, NNOD // 2:] = -1
        if heat:
            elems = elems.copy()
            elems[mixed, 1] = -1
        sel = np.nonzero(mixed & (active == C_ACTIVE))[0]
        # Gathered rows carry the four heat columns either way (zero without heat)
        qsel = q[sel] if heat else np.zeros((sel.shape[0], 4))
        rows = np.concatenate([keys[sel], nodes[sel], weights[sel],
                               fnod[sel].reshape(-1, 2 * NNOD), qsel], axis=1)
        # Columns: keys 0:4, nodes 4:12 (the grain side's cleared), weights, forces, heat
        rows[:, 4:4 + NNOD // 2] = -1
        with ctx.timers.phase("contact_exchange"):
            got = allgather_rows(ctx.comm, rows) if ctx.comm.size > 1 else rows
        if got.shape[0] == 0:
            self._add(st, ctx, order, active, local_nodes, weights, fnod, q, elems)
            return
        c_w, c_f, c_q = 4 + NNOD, 4 + 2 * NNOD, 4 + 4 * NNOD
        gkeys = got[:, 0:4].astype(np.int64)
        k_all = np.concatenate([keys, gkeys])
        n_all = np.concatenate([local_nodes, got[:, 4:c_w].astype(np.int64)])
        w_all = np.concatenate([weights, got[:, c_w:c_f]])
        f_all = np.concatenate([fnod, got[:, c_f:c_q].reshape(-1, NNOD, 2)])
        a_all = np.concatenate([active, np.full(got.shape[0], C_ACTIVE, np.int8)])
        q_all = e_all = None
        if heat:
            q_all = np.concatenate([q, got[:, c_q:c_q + 4]])
            # The block side's element of a gathered row: its body (by gid) and element
            g0 = ctx.nglobal
            blk = np.searchsorted(s.gid[:g0], gkeys[:, 2])
            gel = np.stack([np.full(got.shape[0], -1), s.estart[blk] + gkeys[:, 3]], axis=1)
            e_all = np.concatenate([elems, gel]).astype(np.int64)
        self._add(st, ctx, lexorder(k_all), a_all, n_all, w_all, f_all, q_all, e_all)

    def _add(self, st, ctx, order, active, nodes, weights, fnod, q, elems, forces=True):
        """Forces (with forces) and heat (q not None) of the contacts in the given order to
        owned nodes, and the heat to the owned elements of the two sides (elems) by
        mechanism."""
        s = st.store
        if forces:
            accumulate_sorted(order, active, nodes, fnod, s.nn_own, st.fc)
        if q is not None:
            ctx.heat.add_contact_heat(order, active, nodes, weights, q[:, 0], q[:, 1], s.nn_own)
            accumulate_element_heat_sorted(order, active, elems, q[:, 0], q[:, 1], q[:, 2],
                                           q[:, 3], s.ne_own, s.eheat)

    def _bookkeeping(self, st, ctx, keys, active, us_out, res, elems):
        """New history table; contact energy and friction per body of side A (counted once)."""
        s = st.store
        self.stored = np.zeros(s.nbody)
        fric, damp = np.zeros(s.nbody), np.zeros(s.nbody)
        s.hkey, s.hval = contact_bookkeeping(active, keys, us_out, res, elems, s.elem_body,
                                             s.isglobal, s.nb_own, ctx.comm.rank == 0,
                                             self.stored, fric, damp)
        if self.friction:
            s.contact_acc[:, CACC_FRIC] += fric
        if self.zeta_max > 0.0:
            s.contact_acc[:, CACC_DAMP] += damp

    # ------------------------------------------------------------------ step size, energy
    def stable_dt(self, st, ctx):
        """Smallest stable step of: any contact that may begin (initial stiffness over a whole
        boundary edge), the active contacts (their stiffness hardens), and the step in which
        the fastest approach closes APPROACH x delta_max."""
        s = st.store
        vmax = max_speed(s.v, 0, s.nn_own)
        dt = APPROACH * self.delta_min / (2.0 * vmax) if vmax > 0.0 else np.inf
        dt = min(dt, entry_dt_min(s.x, s.conn, s.ebnd, s.elen, self.mass, 0, s.ne_own,
                                  self.kn0_max, self.zeta_max))
        if self.last is None:
            return dt
        last = self.last
        return min(dt, contact_dt_min(last["active"], last["res"], self.zeta_max))

    def dt_limiter(self, st, ctx, dt):
        """Words naming what limits the step to dt (for the time.dt_min error): the contact
        or boundary element whose limit it is, with body and element ids."""
        s = st.store
        if self.last is not None:
            last = self.last
            for p in np.nonzero(last["active"] == C_ACTIVE)[0]:
                sl = slice(p, p + 1)
                if contact_dt_min(last["active"][sl], last["res"][sl], self.zeta_max) <= dt:
                    k = last["keys"][p]
                    other = f"wall {-1 - k[2]}" if k[2] < 0 else f"body {k[2]} element {k[3]}"
                    return (f"the stiffness of the contact between body {k[0]} element {k[1]} "
                            f"and {other}")
        for e in range(s.ne_own):
            if entry_dt_min(s.x, s.conn, s.ebnd, s.elen, self.mass, e, e + 1, self.kn0_max,
                            self.zeta_max) <= dt:
                return (f"contact.kn0 on the edges of body {s.elem_gid[e]} element "
                        f"{s.elem_loc[e]}")
        return "the approach speed of the contacts (delta_max / speed)"

    def start_work(self, st, ctx):
        """At t = 0: the contact work accumulators start at minus the stored energy, so that
        the absorbed energy (energy.py, contact_loss) counts from the initial state."""
        st.store.acc[:, ACC_CWORK] -= self.stored

    def frame_values(self, st, ctx, name, nodes, elems):
        """contact_force: the contacts' share of the nodal forces."""
        return st.fc[nodes]

    def energy_terms(self, st, ctx, out):
        s = st.store
        nb = s.nb_own
        stored = self.stored[:nb] if self.stored.shape[0] >= nb else np.zeros(nb)
        out["contact"] = stored
        fric, damp = s.contact_acc[:nb, CACC_FRIC], s.contact_acc[:nb, CACC_DAMP]
        out["friction"] = fric
        out["contact_damping"] = damp
        # What the contacts absorbed beyond their stored energy and friction: the work done
        # on them (minus the work their forces did on the bodies) less those two
        out["contact_loss"] = -s.acc[:nb, ACC_CWORK] - stored - fric - damp


def check_contact_scene(resolved):
    """Walls need the law of the [contact] table."""
    walls = resolved.get("walls", {})
    if any(walls.get(s, "none") != "none" for s in WALL_SIDES) and "contact" not in resolved:
        raise InputError("walls: contact walls need the [contact] table (kn0, delta_max)")
