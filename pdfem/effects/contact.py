"""Contact between bodies (report sec. 5): the overlap law, found on the cell grid.

Detection has two levels. At every rebuild the cell grid gives candidate grain pairs: grains
in the same or neighbouring cells whose bounding boxes (inflated by the skin) overlap; no pair
can come into contact before the next rebuild, since rebuilds happen whenever a node has moved
half the skin. Every step, the boundary elements of candidate pairs whose boxes overlap are
clipped against each other (pdfem.kernels.contact). Blocks (global bodies) are checked against
every owned grain each step; domain walls against every owned boundary element.

Bit-for-bit reproducibility: each pair is evaluated in canonical orientation (lower global key
first) by every rank that owns one side; forces are added to owned nodes in the order of the
contact keys (gid_a, elem_a, gid_b, elem_b). A block's nodes receive the forces of contacts
computed on every rank, so those contributions are gathered and every rank adds all of them
in key order. Contact history (the elastic shear displacement) is kept per key, sorted, and
travels with a grain when it migrates.
"""

import math

import numpy as np
from mpi4py import MPI

from pdfem.effects.base import Effect
from pdfem.errors import InputError
from pdfem.kernels import contact_law as L
from pdfem.kernels.broad_phase import candidate_pairs, element_bboxes, wall_crossings
from pdfem.kernels.contact import (
    C_ACTIVE,
    NNOD,
    NRES,
    R_DAMP,
    R_DELTA,
    R_DISS,
    R_ENERGY,
    R_WIDTH,
    element_pair_forces,
    element_wall_forces,
)
from pdfem.kernels.contact_step import accumulate_sorted, contact_dt_min, entry_dt_min, max_speed
from pdfem.kernels.heat import (
    accumulate_element_heat_sorted,
    accumulate_heat_sorted,
    contact_heat,
)
from pdfem.kernels.integrate import ACC_CDAMP, ACC_CWORK, ACC_FRIC
from pdfem.kernels.neighbours import (
    body_boxes,
    grain_pairs,
    key_spans,
    lookup_sorted,
    pack_keys,
)
from pdfem.parallel.exchange import body_centroids
from pdfem.parallel.mpi import allgather_rows

# Beyond RCAP * delta_max the hardening law continues along its tangent (see contact_law)
RCAP = 0.95
# A step may close a gap by at most this fraction of delta_max (two bodies each moving at the
# fastest node speed): the overlap law must see a contact before it is deep
APPROACH = 0.1
# Outward normals of the domain walls (pointing into the domain) and their box coordinate
WALL_SIDES = {"left": ((1.0, 0.0), 0), "bottom": ((0.0, 1.0), 1), "right": ((-1.0, 0.0), 2),
              "top": ((0.0, -1.0), 3)}


def _lexorder(keys):
    """Indices sorting (n, 4) int64 keys lexicographically (stable).

    When the spans of the four columns multiply to less than 2^63 the rows are packed into
    one int64 in mixed radix (an order-preserving map) and sorted once, about 15x faster
    than np.lexsort; otherwise np.lexsort. Both give the same permutation.
    """
    if keys.shape[0] < 2:
        return np.arange(keys.shape[0])
    lo, span = np.empty(4, np.int64), np.empty(4, np.int64)
    key_spans(keys, lo, span)
    # Mixed-radix packing, exact while the product of the spans fits in int64
    if math.prod(int(s) for s in span) < 2**63:
        packed = np.empty(keys.shape[0], np.int64)
        pack_keys(keys, lo, span, packed)
        return np.argsort(packed, kind="stable")
    return np.lexsort((keys[:, 3], keys[:, 2], keys[:, 1], keys[:, 0]))


class Contact(Effect):
    """The report's frictional, no-tension, hardening contact (scene tables [contact], [walls])."""

    name = "contact"

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
        self._wall_out = np.zeros((2, 1024), np.int64)
        self.friction = bool(self.law[:, :, L.P_MU].max() > 0 or any(w[2] > 0 for w in self.walls))
        # Heat across contacts (set by the contact_conductance / friction_heating effects)
        self.heat_h = 0.0
        self.heat_fraction = 0.0
        self.gpairs = np.zeros((0, 2), np.int64)
        self._out = np.zeros((1024, 2), np.int64)
        self._last = None

    def setup(self, sim):
        self.after_rebuild(sim)

    # ------------------------------------------------------------------ detection
    def after_rebuild(self, sim):
        """Candidate grain pairs from the cell grid (first level of detection)."""
        s, g0 = sim.store, sim.nglobal
        n = s.nbody - g0
        cent = np.empty((n, 2))
        body_centroids(s.x, s.nstart, s.nn, g0, s.nbody, cent)
        cells = sim.grid.cell_of(cent) if n else np.zeros(0, np.int64)
        bbox = np.empty((s.nelem, 4))
        element_bboxes(s.x, s.conn, 0, s.nelem, bbox)
        boxes = np.empty((s.nbody, 4))
        body_boxes(bbox, s.estart, s.ne, 0, s.nbody, boxes)
        owned = (np.arange(g0, s.nbody) < s.nb_own).astype(np.int8)
        pairs = grain_pairs(cells.astype(np.int64), owned, boxes[g0:], sim.grid.nx, sim.grid.ny,
                            sim.skin)
        self.gpairs = pairs + g0

    def _body_pairs(self, sim, boxes):
        """Grain pairs of the last rebuild, plus owned grains near each block, block pairs."""
        s, g0 = sim.store, sim.nglobal
        parts = [self.gpairs]
        own = np.arange(g0, s.nb_own)
        for g in range(g0):
            b = boxes[g]
            near = own[(boxes[own, 0] <= b[2]) & (boxes[own, 2] >= b[0])
                       & (boxes[own, 1] <= b[3]) & (boxes[own, 3] >= b[1])]
            parts.append(np.stack([near, np.full(near.shape[0], g)], axis=1))
            for h in range(g + 1, g0):
                parts.append(np.array([[g, h]], np.int64))
        return np.concatenate(parts).astype(np.int64)

    def _element_pairs(self, sim, bbox, bpairs):
        """Boundary-element pairs of the candidate bodies whose boxes overlap."""
        s = sim.store
        e0, e1 = s.estart, s.estart + s.ne
        while True:
            n = candidate_pairs(bbox, s.ebnd, s.elem_gid, s.elem_loc, e0, e1, bpairs, 0.0,
                                self._out)
            if n <= self._out.shape[0]:
                return self._out[:n].copy()
            self._out = np.zeros((2 * n, 2), np.int64)

    def _wall_elements(self, sim, bbox):
        """(elements, wall index) of owned boundary elements crossing a wall line."""
        s = sim.store
        if not self.walls:
            return np.zeros(0, np.int64), np.zeros(0, np.int64)
        while True:
            m = wall_crossings(bbox, s.ebnd, s.ne_own, self._wall_p0, self._wall_n,
                               self._wall_out[0], self._wall_out[1])
            if m <= self._wall_out.shape[1]:
                return self._wall_out[0, :m].copy(), self._wall_out[1, :m].copy()
            self._wall_out = np.zeros((2, 2 * m), np.int64)

    # ------------------------------------------------------------------ forces
    def contact_forces(self, sim):
        """Evaluate every contact this rank needs and add the forces in key order."""
        s = sim.store
        with sim.timers.phase("contact_detection"):
            bbox = np.empty((s.nelem, 4))
            element_bboxes(s.x, s.conn, 0, s.nelem, bbox)
            boxes = np.empty((s.nbody, 4))
            body_boxes(bbox, s.estart, s.ne, 0, s.nbody, boxes)
            pairs = self._element_pairs(sim, bbox, self._body_pairs(sim, boxes))
            welems, wids = self._wall_elements(sim, bbox)
        with sim.timers.phase("contact_forces"):
            self._evaluate(sim, pairs, welems, wids)

    def _evaluate(self, sim, pairs, welems, wids):
        s = sim.store
        npair, nwall = pairs.shape[0], welems.shape[0]
        n = npair + nwall
        # Global keys: (gid_a, elem_a, gid_b, elem_b); a wall is (gid, elem, -1 - wall, 0)
        keys = np.empty((n, 4), np.int64)
        a, b = pairs[:, 0], pairs[:, 1]
        keys[:npair] = np.stack([s.elem_gid[a], s.elem_loc[a], s.elem_gid[b], s.elem_loc[b]], 1)
        keys[npair:] = np.stack([s.elem_gid[welems], s.elem_loc[welems], -1 - wids,
                                 np.zeros(nwall, np.int64)], 1)
        order = _lexorder(keys)
        us_in = np.empty(n)
        lookup_sorted(keys, order, s.hkey, s.hval, us_in)
        # Law parameters of each contact's material pair (walls: the pair with itself)
        params = np.empty((n, L.NPAR))
        params[:npair] = self.law[s.emat[a], s.emat[b]]
        params[npair:] = self.law[s.emat[welems], s.emat[welems]]
        for w, (_, _, mu) in enumerate(self.walls):
            params[npair:][wids == w, L.P_MU] = mu
        active = np.empty(n, np.int8)
        nodes = np.empty((n, NNOD), np.int64)
        weights = np.empty((n, NNOD))
        fnod = np.empty((n, NNOD, 2))
        us_out = np.empty(n)
        res = np.empty((n, NRES))
        sl = slice(0, npair)
        dt = getattr(sim, "dt", 0.0)
        bad = element_pair_forces(s.x, sim.du, s.conn, s.ebnd, s.elem_gid, s.elem_loc, s.elen,
                                  pairs, params[sl], us_in[sl], active[sl], nodes[sl],
                                  weights[sl], fnod[sl], us_out[sl], res[sl], s.m, dt)
        sl = slice(npair, n)
        if nwall:
            p0, nrm = self._wall_p0[wids], self._wall_n[wids]
            bad += element_wall_forces(s.x, sim.du, s.conn, s.ebnd, s.elen, welems, p0, nrm,
                                       params[sl], us_in[sl], active[sl], nodes[sl],
                                       weights[sl], fnod[sl], us_out[sl], res[sl], s.m, dt)
        self._check(sim, keys, active, res, bad)
        self._apply(sim, keys, order, active, nodes, weights, fnod, res, pairs, welems)
        self._bookkeeping(sim, keys, order, active, us_out, res, pairs, welems)
        self._last = {"active": active, "nodes": nodes, "res": res, "fnod": fnod, "keys": keys}

    def _check(self, sim, keys, active, res, bad):
        """Guards: a degenerate overlap, or a mean overlap delta = area / L (the law's) beyond
        delta_max."""
        deep = (active == C_ACTIVE) & (res[:, R_DELTA] > self.delta_max)
        if bad or deep.any():
            p = int(np.nonzero((active < 0) | deep)[0][0])
            k = keys[p]
            what = (f"deeper than contact.delta_max (delta = {res[p, R_DELTA]:.3e} m)"
                    if deep[p] else "degenerate (one element inside the other)")
            other = f"wall {-1 - k[2]}" if k[2] < 0 else f"body {k[2]} element {k[3]}"
            sim.fail(f"check contact overlap: the contact between body {k[0]} element {k[1]} "
                     f"and {other} is {what}")

    def _apply(self, sim, keys, order, active, nodes, weights, fnod, res, pairs, welems):
        """Add forces (and contact heat) to owned nodes in key order (order sorts keys);
        block-side rows are gathered from all ranks."""
        s = sim.store
        # Heat of each contact on its two sides (this step, over sim.dt), its friction part,
        # and the elements of the two sides (-1: a wall)
        heat = (self.heat_h > 0.0 or self.heat_fraction > 0.0) and hasattr(sim, "dt")
        q = elems = None
        if heat:
            q = np.zeros((active.shape[0], 4))
            contact_heat(active, nodes, weights, res, s.T, self.heat_h, self.heat_fraction,
                         sim.dt, R_WIDTH, R_DISS, q[:, 0], q[:, 1], q[:, 2], q[:, 3])
            elems = np.concatenate([pairs, np.stack([welems, np.full(welems.shape[0], -1)],
                                                    axis=1)]).astype(np.int64)
        # No blocks: every contact is local, already sorted
        if sim.nglobal == 0:
            self._add(sim, order, active, nodes, weights, fnod, q, elems)
            return
        npair = pairs.shape[0]
        isg = s.isglobal[s.elem_body]
        mixed = np.zeros(active.shape[0], bool)
        mixed[:npair] = isg[pairs[:, 0]] != isg[pairs[:, 1]]
        local_nodes = nodes.copy()
        # Canonical orientation puts the grain (lower gid) first: its block side is gathered
        local_nodes[mixed, NNOD // 2:] = -1
        if heat:
            elems[mixed, 1] = -1
        sel = np.nonzero(mixed & (active == C_ACTIVE))[0]
        # Gathered rows carry the four heat columns either way (zero without heat)
        qsel = q[sel] if heat else np.zeros((sel.shape[0], 4))
        rows = np.concatenate([keys[sel], nodes[sel], weights[sel],
                               fnod[sel].reshape(-1, 2 * NNOD), qsel], axis=1)
        # Columns: keys 0:4, nodes 4:12 (the grain side's cleared), weights, forces, heat
        rows[:, 4:4 + NNOD // 2] = -1
        got = allgather_rows(sim.comm, rows) if sim.comm.size > 1 else rows
        if got.shape[0] == 0:
            self._add(sim, order, active, local_nodes, weights, fnod, q, elems)
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
            g0 = sim.nglobal
            blk = np.searchsorted(s.gid[:g0], gkeys[:, 2])
            gel = np.stack([np.full(got.shape[0], -1), s.estart[blk] + gkeys[:, 3]], axis=1)
            e_all = np.concatenate([elems, gel]).astype(np.int64)
        self._add(sim, _lexorder(k_all), a_all, n_all, w_all, f_all, q_all, e_all)

    def _add(self, sim, order, active, nodes, weights, fnod, q, elems):
        """Forces (and heat, q not None) of the contacts in the given order to owned nodes,
        and the heat to the owned elements of the two sides (elems) by mechanism."""
        s = sim.store
        accumulate_sorted(order, active, nodes, fnod, s.nn_own, sim.fc)
        if q is not None:
            accumulate_heat_sorted(order, active, nodes, weights, q[:, 0], q[:, 1], s.nn_own,
                                   sim.heat.src)
            accumulate_element_heat_sorted(order, active, elems, q[:, 0], q[:, 1], q[:, 2],
                                           q[:, 3], s.ne_own, s.eheat)

    def _bookkeeping(self, sim, keys, order, active, us_out, res, pairs, welems):
        """New history table; contact energy and friction per body of side A (counted once)."""
        s = sim.store
        on = order[active[order] == C_ACTIVE]
        s.hkey, s.hval = keys[on], us_out[on]
        body_a = np.concatenate([s.elem_body[pairs[:, 0]], s.elem_body[welems]])[on]
        mine = body_a < s.nb_own
        if sim.comm.rank != 0:
            mine &= s.isglobal[body_a] == 0
        # Per-body sums in key order (bincount adds in the order given)
        rows, bodies = on[mine], body_a[mine]
        self.energy = np.bincount(bodies, res[rows, R_ENERGY], minlength=s.nbody)
        if self.friction:
            s.acc[:, ACC_FRIC] += np.bincount(bodies, res[rows, R_DISS], minlength=s.nbody)
        if self.zeta_max > 0.0:
            s.acc[:, ACC_CDAMP] += np.bincount(bodies, res[rows, R_DAMP], minlength=s.nbody)

    # ------------------------------------------------------------------ step size, energy
    def stable_dt(self, sim):
        """Smallest stable step of: any contact that may begin (initial stiffness over a whole
        boundary edge), the active contacts (their stiffness hardens), and the step in which
        the fastest approach closes APPROACH x delta_max."""
        s = sim.store
        vmax = max_speed(s.v, 0, s.nn_own)
        dt = APPROACH * self.delta_min / (2.0 * vmax) if vmax > 0.0 else np.inf
        dt = min(dt, entry_dt_min(s.x, s.conn, s.ebnd, s.elen, s.m, 0, s.ne_own, self.kn0_max,
                                  self.zeta_max))
        if self._last is None:
            return dt
        last = self._last
        return min(dt, contact_dt_min(last["active"], last["res"], self.zeta_max))

    def dt_limiter(self, sim, dt):
        """Words naming what limits the step to dt (for the time.dt_min error): the contact
        or boundary element whose limit it is, with body and element ids."""
        s = sim.store
        if self._last is not None:
            last = self._last
            for p in np.nonzero(last["active"] == C_ACTIVE)[0]:
                sl = slice(p, p + 1)
                if contact_dt_min(last["active"][sl], last["res"][sl], self.zeta_max) <= dt:
                    k = last["keys"][p]
                    other = f"wall {-1 - k[2]}" if k[2] < 0 else f"body {k[2]} element {k[3]}"
                    return (f"the stiffness of the contact between body {k[0]} element {k[1]} "
                            f"and {other}")
        for e in range(s.ne_own):
            if entry_dt_min(s.x, s.conn, s.ebnd, s.elen, s.m, e, e + 1, self.kn0_max,
                            self.zeta_max) <= dt:
                return (f"contact.kn0 on the edges of body {s.elem_gid[e]} element "
                        f"{s.elem_loc[e]}")
        return "the approach speed of the contacts (delta_max / speed)"

    def start_work(self, sim):
        """At t = 0: the contact work accumulators start at minus the stored energy, so that
        the absorbed energy (energy.py, contact_loss) counts from the initial state."""
        sim.store.acc[:, ACC_CWORK] -= self.energy

    def energy_terms(self, sim, out):
        e = getattr(self, "energy", None)
        out["contact"] = e[: sim.store.nb_own] if e is not None and e.shape[0] >= \
            sim.store.nb_own else np.zeros(sim.store.nb_own)


def count_contacts(comm, active):
    """Number of active contacts over all ranks (diagnostic)."""
    return comm.allreduce(int((active == C_ACTIVE).sum()), op=MPI.SUM)


def check_contact_scene(resolved):
    """Walls need the law of the [contact] table."""
    walls = resolved.get("walls", {})
    if any(walls.get(s, "none") != "none" for s in WALL_SIDES) and "contact" not in resolved:
        raise InputError("walls: contact walls need the [contact] table (kn0, delta_max)")
