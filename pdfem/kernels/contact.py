"""Element-to-element and element-to-wall contact forces (report sec. 5, figs. 4-7).

A contact is a pair of boundary elements of two different bodies; under the potential law
(contact_potential) also a boundary element and an element inside the other body (no boundary
edge, contact length 0), a pair that carries the normal force only: the pair's length is the
boundary element's, it holds no shear and conducts no heat (width 0), and the contact point's
weights lie on the inside element's nearest edge. The kernels compute, for every candidate
pair, the overlap polygon, the contact frame and the forces of the law in contact_law.py on the
nodes of both elements. They never add into the global force array:
``contact_step.accumulate_sorted`` does that, in an order the caller chooses (contacts sorted by
global key), so that a node's force is the same sum on any number of ranks.

Normal force: the gradient of a stored energy. The report's law gives the traction t_n as a
function of the mean overlap delta; here delta = A / L with A the pair's overlap area and L a
length fixed for the pair: the smaller of the two elements' contact lengths ``elen``, their
longest boundary edges as built. For a flat contact over a whole edge that is the width, and
the force below is the report's; a corner pressed into a flat, whose overlap spans two edges,
is up to width / L stiffer than the report's delta = A / width would make it.
The stored energy is E = L phi(A / L), phi(delta) = int_0^delta t_n, and the nodal forces are
f_k = -dE/dx_k = -t_n dA/dx_k. (One traction per body pair, from the sum of its element pairs'
areas, was tried: a pair that joins a loaded body pair then starts at that traction times its
whole chord, a force jump that sets thin element tips chattering.)

dA/dx_k is exact: moving an element's edge sweeps the overlap's area along the part of the
overlap boundary lying on that edge, so for each overlap edge (outward normal x length N,
midpoint at parameter s of the element edge from node i to node j) node i gets (1 - s) N and
node j gets s N. Every overlap edge contributes, of both elements, so a contact loads up to
eight nodes. The forces sum to zero (the overlap boundary is closed) and have no moment (A is
invariant under rigid rotation); the work they do is exactly the change of E, so contacts
neither create nor destroy energy. For a flat contact of width w = L this is the report's force
w t_n(delta) on the contact edges; the report's rule of one force at the nearest edge, with
delta = A / w and w changing as the overlap grows, is not the gradient of any energy and creates
energy at a rate that grows with the impact speed.

Contact frame, for the shear. Let N_A (N_B) be the sum of (outward normal x length) of the
overlap edges lying on *grain-boundary* edges (ebnd = 1) of A (B); the unit normal n is
N_A - N_B normalised, from A into B (the chord normal of the report's lens, exact also for a
flat contact cut by an interior element edge); if it vanishes or makes an obtuse angle with
the sum over all of A's overlap edges, that sum is used. The contact width w is the extent of
the overlap along t = (-n_y, n_x) (used by the contact conductance), the contact point c the
overlap centroid. The shear force ks L u_s acts along t at c, shared between the two nodes of
each side's boundary edge nearest to c with the weights of c's projection on it.

Normal damping (contact.damping = zeta > 0): a dashpot on the overlap area,
contact_law.damped_traction; its dissipation in a step is (t - t_n) dA.

Orientation. Each pair is evaluated internally with the element of lower global key (egid,
eloc) as A, whatever order the caller gives, so both orders give bit-identical (mirrored)
results. Outputs refer to the caller's order: pairs[p, 0] is "A". The overlap is found by
clipping A by B's edge lines, which needs B convex; a deformed B that is not convex is split
into two triangles that each clip A (contact_frame.pair_overlap), so the area and its gradient
stay exact for any shapes the elements take.

Output layout per contact p: active[p] (int8, codes C_*); nodes[p, 0:4] A's nodes, nodes[p, 4:8]
B's (-1 for a wall); fnod[p, k] the force on nodes[p, k]; weights[p, k] the weight of node k in
the contact point (nonzero on the nearest boundary edge of each side: the shear's and the
contact heat's interpolation); us_out[p] the new shear history; res[p, :] the scalars R_*.

One kernel evaluates contacts: contact_pass, over a list of candidates (element pairs and
element-wall pairs). A step passes the key-sorted candidates of the last rebuild
(pdfem.effects.contact) and gets one output row per contact that touches, in key order, so the
forces are added in that order without a sort; element_pair_forces and element_wall_forces
pass their own lists and get one row per candidate. The pass is one loop with the per-pair
geometry in three calls (the clip, the polygon's frame, the nearest edges): numba counts
references to every array passed through a call, so a pair evaluated through many small
functions costs several times its arithmetic.
"""

import numpy as np
from numba import njit

from pdfem.kernels.broad_phase import element_bboxes
from pdfem.kernels.contact_frame import (
    NNOD,
    alloc_overlap_work,
    overlap_extent,
    pair_overlap,
    polygon_frame,
    unit_normal,
)
from pdfem.kernels.contact_keys import key_less
from pdfem.kernels.contact_law import (
    P_DMAX,
    P_KN0,
    P_KS,
    P_LAW,
    P_MU,
    P_RCAP,
    P_ZETA,
    damped_traction,
    effective_mass,
    normal_force,
    shear_update,
)
from pdfem.kernels.contact_potential import (
    corner_box,
    corner_extent,
    pair_potential,
    wall_potential,
)
from pdfem.kernels.overlap import (
    K_P,
    K_Q,
    K_X,
    MAXV,
    OV_INSIDE,
    OV_NONE,
    OV_OK,
    OV_OVERFLOW,
    SLIVER,
    T_KIND,
    T_SRC,
    alloc_clip_buffers,
    bbox_scale2,
    halfplane_into,
)

# Relative margin (of the elements' size) beyond which a contact's width or centroid is out of
# its elements' bounds: far above rounding, far below any true overlap's size
BOUND_TOL = 1e-9

# Columns of res[p, :]
R_FN = 0  # normal force on A along n, tension positive (<= 0) [N/m]
R_FS = 1  # shear force on A along t [N/m]
R_ENERGY = 2  # stored elastic energy, normal + shear [J/m]
R_DISS = 3  # frictional dissipation of this step [J/m]
R_STIFF = 4  # tangent k_t = dt_n/d(delta) of the traction law at delta [Pa/m]
R_DELTA = 5  # mean normal overlap delta = area / L [m]
R_WIDTH = 6  # width of the overlap along t [m]
R_NX = 7  # unit normal from A (pairs[p, 0]) into B, x
R_NY = 8  # unit normal, y
R_CX = 9  # contact point (overlap centroid), x
R_CY = 10  # contact point, y
R_DAMP = 11  # dissipation of the normal damping in this step, (t - t_n) dA [J/m]
R_LEN = 12  # the pair's length L [m]
R_KSL = 13  # shear stiffness ks L [N/m^2]
R_MEFF = 14  # effective mass of the two sides (their lightest loaded nodes) [kg/m]
R_AREA = 15  # overlap area [m^2]
NRES = 16

# Codes of active[p]; negative codes are guards the caller must treat as errors
C_NONE = 0  # no overlap: no force, history reset
C_ACTIVE = 1  # in contact
C_INSIDE = -1  # one element inside the other (or behind the wall): penetration too deep
C_NOEDGE = -2  # an element of the pair has no boundary edge
C_NONORMAL = -3  # the contact normal is undefined (symmetric overlap)
C_OVERFLOW = -4  # clip buffer overflow (cannot happen for convex quads)


@njit(cache=True)
def _clear(r, us_keep, code, active, nodes, weights, fnod, us_out, res):
    """Row r of a contact that applies no force (history kept for guards, reset otherwise)."""
    active[r] = code
    for k in range(NNOD):
        nodes[r, k] = -1
        weights[r, k] = 0.0
        fnod[r, k, 0] = 0.0
        fnod[r, k, 1] = 0.0
    us_out[r] = us_keep
    for k in range(res.shape[1]):
        res[r, k] = 0.0


@njit(cache=True)
def contact_pass(x, du, m, conn, ebnd, egid, eloc, elen, edep, eapex, emat, law, nmat, lrow,
                 wall_p0, wall_n, wall_mu, cand, hkey, hval, us_in, dense, general, dt, bbox, fc,
                 n_owned, active, keys, elems, nodes, weights, fnod, us_out, res, period=0.0):
    """Evaluate the candidate contacts cand (nc, 2): element pairs (a, b) of different bodies and
    element-wall pairs (e, -1 - w). With periodic sides cand is (nc, 3), its third column the
    shift k of the pair: b is met k periods (period [m]) to the right, its corners and box
    shifted by k period in x (-k when the pair is turned to put the lower key first).

    x, du (nn, 2): positions and displacement increments of the step (du / dt is the velocity
    the normal damping sees; dt = 0: none); m (nn,) lumped masses; conn (ne, 4) int64 CCW;
    ebnd (ne, 4) int8 boundary-edge flags; egid, eloc (ne,) int64 global element key; elen
    (ne,) contact lengths; edep (ne, 4), eapex (ne,) the potential law's values at the
    elements' corners and centroids (grain_depth.element_depths). The law of a candidate is
    the row law[lrow[c]] of law (nrow, NPAR) (contact_law.P_*), or with lrow empty the row
    emat[a] * nmat + emat[b] of the material pair (emat (ne,) element materials; a wall: the
    element's material with itself); a wall's friction is wall_mu[w]. Wall w is the half-plane
    {p : n.(p - p0) < 0}, p0 = wall_p0[w], n = wall_n[w] its unit normal out of the wall into
    the domain. The shear history is us_in[c],
    or with us_in empty the value of the candidate's key in the sorted table hkey (nh, 4),
    hval (nh,) (0 if absent; the candidates must then be sorted by key: a merge).

    A candidate is evaluated when the step's exact test of the broad phase passes (the two
    elements' boxes overlap; the element's box reaches behind the wall); bbox (ne, 4) is
    scratch for the boxes.

    Outputs (module docstring, plus keys (4,) the global contact key, a wall's (gid, elem,
    -1 - w, 0), and elems the two elements, -1 for a wall): with dense, row c for candidate c
    (C_NONE rows cleared); otherwise one row per contact that touches or is guarded, in
    candidate order, where the arrays' last row is scratch: contacts that do not fit land
    there, and the caller calls again with room for all. With fc (nn, 2) not empty, each
    contact's nodal forces are added to fc at its owned nodes (< n_owned) as its row is
    written: contact_step.accumulate_sorted in row order, without reading the rows again (every
    contact's, also those that land in the scratch row). general: every pair through the clip
    library (contact_frame.pair_overlap), the convex ones too, which the pass otherwise
    evaluates in its own loop with the same operations (the reference the tests compare it
    with). Returns (rows written or needed, guarded contacts, candidates evaluated).
    """
    px, py, pt = alloc_clip_buffers()
    q4, tri, tmap = alloc_overlap_work()
    # The potential law's own clip buffers and triangle (slot 0 of px holds the overlap)
    qx, qy, qt = alloc_clip_buffers()
    qtri = np.empty((3, 2))
    xa = np.empty((4, 2))
    xb = np.empty((4, 2))
    g = np.empty((NNOD, 2))
    wgt = np.empty(NNOD)
    nod = np.empty(NNOD, np.int64)
    last = active.shape[0] - 1
    nh = hkey.shape[0]
    by_row = lrow.shape[0] > 0
    add = fc.shape[0] > 0
    lookup = us_in.shape[0] == 0
    q = 0
    h = 0
    nbad = 0
    nev = 0
    held = -1
    shifted = cand.shape[1] > 2
    # Every element's box (broad_phase.element_bboxes: the candidates' test)
    element_bboxes(x, conn, 0, conn.shape[0], bbox)
    for c in range(cand.shape[0]):
        a = cand[c, 0]
        b = cand[c, 1]
        kp = cand[c, 2] if shifted else 0
        wall = b < 0
        w = -1 - b
        wnx = 0.0
        wny = 0.0
        # Canonical orientation: A is the element of lower global key (outputs: the caller's)
        flip = not wall and (egid[a] > egid[b] or (egid[a] == egid[b] and eloc[a] > eloc[b]))
        if flip:
            a, b = b, a
            kp = -kp
        # B's shift across the periodic sides (added only when there is one: x + 0.0 would
        # turn a -0.0 into +0.0)
        sh = kp * period
        # The broad phase's exact test of this step, on the elements' boxes
        if wall:
            wnx = wall_n[w, 0]
            wny = wall_n[w, 1]
            lo = min(wnx * (bbox[a, 0] - wall_p0[w, 0]), wnx * (bbox[a, 2] - wall_p0[w, 0])) + \
                min(wny * (bbox[a, 1] - wall_p0[w, 1]), wny * (bbox[a, 3] - wall_p0[w, 1]))
            near = lo < 0.0
        else:
            bx0 = bbox[b, 0]
            bx2 = bbox[b, 2]
            if kp != 0:
                bx0 += sh
                bx2 += sh
            near = (bbox[a, 0] - bx2 <= 0.0 and bx0 - bbox[a, 2] <= 0.0
                    and bbox[a, 1] - bbox[b, 3] <= 0.0 and bbox[b, 1] - bbox[a, 3] <= 0.0)
        # The law of the pair (contact_law); a pair with an element inside its body (no
        # boundary edge, elen 0) is a contact of the potential law only (grain_depth)
        lr = (lrow[c] if by_row else emat[a] * nmat + (emat[a] if wall else emat[b]))
        deep = not wall and not (elen[a] > 0.0 and elen[b] > 0.0)
        if deep and law[lr, P_LAW] == 0.0:
            near = False
        r = c if dense else min(q, last)
        if not near:
            if dense:
                _clear(r, 0.0, C_NONE, active, nodes, weights, fnod, us_out, res)
            continue
        nev += 1
        # Corners of the two elements (A's kept while consecutive candidates share it)
        if a != held:
            for k in range(4):
                xa[k, 0] = x[conn[a, k], 0]
                xa[k, 1] = x[conn[a, k], 1]
            held = a
        if not wall:
            for k in range(4):
                xb[k, 0] = x[conn[b, k], 0]
                xb[k, 1] = x[conn[b, k], 1]
            if kp != 0:
                for k in range(4):
                    xb[k, 0] += sh
        # Overlap, area gradient g and contact frame (n from A into B, width, centroid c)
        width = 0.0
        if wall:
            st, area, cx, cy, _, _, _, _, kw = halfplane_into(xa, wall_p0[w, 0], wall_p0[w, 1],
                                                              wnx, wny, px, py, pt)
            nx = -wnx
            ny = -wny
            length = elen[a]
            if st == OV_OK:
                for k in range(NNOD):
                    g[k, 0] = 0.0
                    g[k, 1] = 0.0
                polygon_frame(px, py, pt, 0, kw, q4, xa, xa, False, ebnd, a, 0, g, 0.0, 0.0,
                              0.0, 0.0)
                lo, hi = overlap_extent(px, py, 0, kw, -ny, nx, px[0, 0], py[0, 0], 0.0, 0.0)
                width = hi - lo
        else:
            length = max(elen[a], elen[b]) if deep else min(elen[a], elen[b])
            # Is B strictly convex, every corner turning left? (contact_frame.is_convex)
            convex = True
            for k in range(4):
                k1 = k + 1 if k + 1 < 4 else 0
                k2 = k1 + 1 if k1 + 1 < 4 else 0
                cr = ((xb[k1, 0] - xb[k, 0]) * (xb[k2, 1] - xb[k1, 1])
                      - (xb[k1, 1] - xb[k, 1]) * (xb[k2, 0] - xb[k1, 0]))
                if not cr > 0.0:
                    convex = False
                    break
            if general or not convex:
                st, area, cx, cy, nx, ny, width = pair_overlap(xa, xb, ebnd, a, b, px, py, pt,
                                                               q4, tri, tmap, g)
            else:
                st, area, cx, cy, nx, ny, width = OV_OK, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0
                # The convex case of contact_frame.pair_overlap written out, operation for
                # operation (no array passes through a call). Early out: A wholly outside an
                # edge line of B (overlap.outside_edge)
                for j in range(4):
                    j1 = (j + 1) % 4
                    lx = xb[j1, 1] - xb[j, 1]
                    ly = xb[j, 0] - xb[j1, 0]
                    out = True
                    for i in range(4):
                        if lx * (xa[i, 0] - xb[j, 0]) + ly * (xa[i, 1] - xb[j, 1]) <= 0.0:
                            out = False
                            break
                    if out:
                        st = OV_NONE
                        break
                kc = 4
                if st == OV_OK:
                    # A clipped by B's four edge lines, slots 0 and 1 (overlap.clip_into; of the
                    # tags, only the kind and the source edge, the two read here)
                    for i in range(4):
                        px[0, i] = xa[i, 0]
                        py[0, i] = xa[i, 1]
                        pt[0, i, T_KIND] = K_P
                        pt[0, i, T_SRC] = i
                    sl = 0
                    for j in range(4):
                        j1 = j + 1 if j + 1 < 4 else 0
                        lx = xb[j1, 1] - xb[j, 1]
                        ly = xb[j, 0] - xb[j1, 0]
                        x0 = xb[j, 0]
                        y0 = xb[j, 1]
                        d = 1 - sl
                        # One Sutherland-Hodgman step (overlap.clip_halfplane)
                        kn = 0
                        js = kc - 1
                        ss = lx * (px[sl, js] - x0) + ly * (py[sl, js] - y0)
                        for je in range(kc):
                            se = lx * (px[sl, je] - x0) + ly * (py[sl, je] - y0)
                            src = pt[sl, js, T_SRC]
                            kind = K_X if src >= 0 else K_Q
                            if se <= 0.0:
                                if ss > 0.0:
                                    if kn >= MAXV:
                                        kn = -1
                                        break
                                    t = ss / (ss - se)
                                    px[d, kn] = px[sl, js] + t * (px[sl, je] - px[sl, js])
                                    py[d, kn] = py[sl, js] + t * (py[sl, je] - py[sl, js])
                                    pt[d, kn, T_KIND] = kind
                                    pt[d, kn, T_SRC] = src
                                    kn += 1
                                if kn >= MAXV:
                                    kn = -1
                                    break
                                px[d, kn] = px[sl, je]
                                py[d, kn] = py[sl, je]
                                pt[d, kn, T_KIND] = pt[sl, je, T_KIND]
                                pt[d, kn, T_SRC] = pt[sl, je, T_SRC]
                                kn += 1
                            elif ss <= 0.0:
                                if kn >= MAXV:
                                    kn = -1
                                    break
                                t = ss / (ss - se)
                                px[d, kn] = px[sl, js] + t * (px[sl, je] - px[sl, js])
                                py[d, kn] = py[sl, js] + t * (py[sl, je] - py[sl, js])
                                pt[d, kn, T_KIND] = kind
                                pt[d, kn, T_SRC] = -1 - j
                                kn += 1
                            js = je
                            ss = se
                        kc = kn
                        sl = d
                        if kc <= 0:
                            break
                    if kc < 0:
                        st = OV_OVERFLOW
                    else:
                        # Area and centroid, fanned from vertex 0 (overlap.polygon_area_centroid)
                        a2 = 0.0
                        sx = 0.0
                        sy = 0.0
                        for i in range(1, kc - 1):
                            ux = px[0, i] - px[0, 0]
                            uy = py[0, i] - py[0, 0]
                            vx = px[0, i + 1] - px[0, 0]
                            vy = py[0, i + 1] - py[0, 0]
                            cr = ux * vy - uy * vx
                            a2 += cr
                            sx += cr * (ux + vx)
                            sy += cr * (uy + vy)
                        if kc >= 3 and a2 != 0.0:
                            area = 0.5 * a2
                            cx = px[0, 0] + sx / (3.0 * a2)
                            cy = py[0, 0] + sy / (3.0 * a2)
                        # A rounding-level sliver is no contact (overlap.bbox_scale2)
                        ex = max(xa[0, 0], xa[1, 0], xa[2, 0], xa[3, 0]) - \
                            min(xa[0, 0], xa[1, 0], xa[2, 0], xa[3, 0])
                        ey = max(xa[0, 1], xa[1, 1], xa[2, 1], xa[3, 1]) - \
                            min(xa[0, 1], xa[1, 1], xa[2, 1], xa[3, 1])
                        ee = max(ex, ey)
                        if area <= SLIVER * (ee * ee):
                            st = OV_NONE
                        else:
                            # Two crossings of the boundaries at different points, or one
                            # element inside the other (overlap._distinct_crossings)
                            first = -1
                            two = False
                            for i in range(kc):
                                if pt[0, i, T_KIND] != K_X:
                                    continue
                                if first < 0:
                                    first = i
                                elif px[0, i] != px[0, first] or py[0, i] != py[0, first]:
                                    two = True
                                    break
                            if not two:
                                st = OV_INSIDE
                if st == OV_OK:
                    # Area gradient and normal sums (contact_frame.polygon_frame, B's edge j
                    # the clip line j)
                    for k in range(NNOD):
                        g[k, 0] = 0.0
                        g[k, 1] = 0.0
                    n0 = 0.0
                    n1 = 0.0
                    s0 = 0.0
                    s1 = 0.0
                    for i in range(kc):
                        i1 = i + 1 if i + 1 < kc else 0
                        src = pt[0, i, T_SRC]
                        ex = py[0, i1] - py[0, i]
                        ey = px[0, i] - px[0, i1]
                        mx = 0.5 * (px[0, i] + px[0, i1])
                        my = 0.5 * (py[0, i] + py[0, i1])
                        if src >= 0:
                            s0 += ex
                            s1 += ey
                            if ebnd[a, src] != 0:
                                n0 += ex
                                n1 += ey
                            j = src
                            j1 = j + 1 if j + 1 < 4 else 0
                            dx = xa[j1, 0] - xa[j, 0]
                            dy = xa[j1, 1] - xa[j, 1]
                            f = ((mx - xa[j, 0]) * dx + (my - xa[j, 1]) * dy) / (dx * dx + dy * dy)
                            r0 = j
                            r1 = j1
                        else:
                            j = -1 - src
                            if ebnd[b, j] != 0:
                                n0 -= ex
                                n1 -= ey
                            j1 = j + 1 if j + 1 < 4 else 0
                            dx = xb[j1, 0] - xb[j, 0]
                            dy = xb[j1, 1] - xb[j, 1]
                            f = ((mx - xb[j, 0]) * dx + (my - xb[j, 1]) * dy) / (dx * dx + dy * dy)
                            r0 = 4 + j
                            r1 = 4 + j1
                        f = min(max(f, 0.0), 1.0)
                        g[r0, 0] += (1.0 - f) * ex
                        g[r0, 1] += (1.0 - f) * ey
                        g[r1, 0] += f * ex
                        g[r1, 1] += f * ey
                    nx, ny = unit_normal(n0, n1, s0, s1)
                    # Width: the extent along the tangent (contact_frame.overlap_extent)
                    lo = 0.0
                    hi = 0.0
                    for i in range(kc):
                        f = (px[0, i] - px[0, 0]) * -ny + (py[0, i] - py[0, 0]) * nx
                        lo = min(lo, f)
                        hi = max(hi, f)
                    width = hi - lo
        if law[lr, P_LAW] != 0.0 and (st == OV_OK or st == OV_INSIDE):
            # The potential law: W, the equivalent area sqrt(W L) and its gradient replace
            # the overlap area and dA/dx (contact_potential)
            if wall:
                wpot = wall_potential(xa, 0.5 * elen[a], wall_p0[w, 0], wall_p0[w, 1], wnx, wny,
                                      qx, qy, qt, qtri, g)
            else:
                wpot = pair_potential(xa, xb, edep[a], eapex[a], edep[b], eapex[b], qx, qy, qt,
                                      qtri, g)
            # The equivalent area; a rounding-level one is no contact, as for the area law
            area = np.sqrt(wpot * length) if wpot > 0.0 and length > 0.0 else 0.0
            if not area > SLIVER * bbox_scale2(xa):
                st = OV_NONE
            else:
                sc = 0.5 / np.sqrt(wpot / length)
                gax = 0.0
                gay = 0.0
                for k in range(NNOD):
                    g[k, 0] *= sc
                    g[k, 1] *= sc
                    if k < 4:
                        gax += g[k, 0]
                        gay += g[k, 1]
                if st == OV_INSIDE or (nx == 0.0 and ny == 0.0):
                    # No chord, or none with a normal (the clip of elements that cross
                    # themselves): the normal is the gradient's for a translation of A, the width
                    # the narrower element's extent along the tangent
                    nx, ny = unit_normal(gax, gay, gax, gay)
                    width = corner_extent(xa, -ny, nx)
                    if not wall:
                        width = min(width, corner_extent(xb, -ny, nx))
                    st = OV_OK
        if st == OV_OK:
            # The overlap lies in both elements: its centroid within their common box and its
            # width within their extents along the tangent (the clip of an element that crosses
            # itself, which a folded corner makes, can put both anywhere)
            lx, hx, ly, hy, ext = corner_box(xa, -ny, nx)
            if not wall:
                bx, bhx, by, bhy, bext = corner_box(xb, -ny, nx)
                lx, hx, ly, hy, ext = (max(lx, bx), min(hx, bhx), max(ly, by), min(hy, bhy),
                                       min(ext, bext))
            # (beyond a rounding margin: a true overlap keeps every bit it had)
            tol = BOUND_TOL * max(hx - lx, hy - ly, ext)
            if width > ext + tol:
                width = ext
            if cx < lx - tol or cx > hx + tol or cy < ly - tol or cy > hy + tol:
                cx = min(max(cx, lx), hx)
                cy = min(max(cy, ly), hy)
        if st == OV_NONE:
            if dense:
                _clear(r, 0.0, C_NONE, active, nodes, weights, fnod, us_out, res)
            continue
        # The global key (the caller's order), and the shear history (looked up only for the
        # pairs that touch: the merge's cursor moves forward all the same)
        ca = cand[c, 0]
        key0 = egid[ca]
        key1 = eloc[ca]
        key2 = b if wall else egid[cand[c, 1]]
        key3 = 0 if wall else eloc[cand[c, 1]]
        if lookup:
            while h < nh and key_less(hkey[h, 0], hkey[h, 1], hkey[h, 2], hkey[h, 3], key0,
                                       key1, key2, key3):
                h += 1
            us = hval[h] if h < nh and not key_less(key0, key1, key2, key3, hkey[h, 0],
                                                     hkey[h, 1], hkey[h, 2], hkey[h, 3]) else 0.0
        else:
            us = us_in[c]
        # The boundary edge of each side nearest to the contact point, and the parameter of
        # the point's projection on it (contact_frame.nearest_edge); the guards
        ka = -1
        sa = 0.0
        kb = -1
        sb = 0.0
        if st != OV_OK:
            code = C_OVERFLOW if st == OV_OVERFLOW else C_INSIDE
        else:
            best = np.inf
            for k in range(4):
                if ebnd[a, k] == 0 and elen[a] > 0.0:
                    continue
                k1 = (k + 1) % 4
                dx = xa[k1, 0] - xa[k, 0]
                dy = xa[k1, 1] - xa[k, 1]
                f = ((cx - xa[k, 0]) * dx + (cy - xa[k, 1]) * dy) / (dx * dx + dy * dy)
                f = min(max(f, 0.0), 1.0)
                rx = xa[k, 0] + f * dx - cx
                ry = xa[k, 1] + f * dy - cy
                d2 = rx * rx + ry * ry
                if d2 < best:
                    best = d2
                    ka = k
                    sa = f
            best = np.inf
            for k in range(0 if wall else 4):
                if ebnd[b, k] == 0 and elen[b] > 0.0:
                    continue
                k1 = (k + 1) % 4
                dx = xb[k1, 0] - xb[k, 0]
                dy = xb[k1, 1] - xb[k, 1]
                f = ((cx - xb[k, 0]) * dx + (cy - xb[k, 1]) * dy) / (dx * dx + dy * dy)
                f = min(max(f, 0.0), 1.0)
                rx = xb[k, 0] + f * dx - cx
                ry = xb[k, 1] + f * dy - cy
                d2 = rx * rx + ry * ry
                if d2 < best:
                    best = d2
                    kb = k
                    sb = f
            if wall:
                code = C_NOEDGE if ka < 0 or not length > 0.0 else C_ACTIVE
            else:
                code = C_ACTIVE
                if nx == 0.0 and ny == 0.0 or ka < 0 or kb < 0 or not length > 0.0:
                    code = C_NONORMAL if ka >= 0 and kb >= 0 and length > 0.0 else C_NOEDGE
        keys[r, 0] = key0
        keys[r, 1] = key1
        keys[r, 2] = key2
        keys[r, 3] = key3
        elems[r, 0] = ca
        elems[r, 1] = -1 if wall else cand[c, 1]
        q += 1
        if code != C_ACTIVE:
            # A guard: no force, the history kept
            nbad += 1
            _clear(r, us, code, active, nodes, weights, fnod, us_out, res)
            continue
        # Nodes and contact-point weights of the two sides (a wall has none)
        for k in range(4):
            nod[k] = conn[a, k]
            nod[4 + k] = -1 if wall else conn[b, k]
            wgt[k] = 0.0
            wgt[4 + k] = 0.0
        wgt[ka] = 1.0 - sa
        wgt[(ka + 1) % 4] = sa
        if not wall:
            wgt[4 + kb] = 1.0 - sb
            wgt[4 + (kb + 1) % 4] = sb
        # dA for a translation of A, and the lightest loaded node of each side
        gax = 0.0
        gay = 0.0
        ma = np.inf
        mb = np.inf
        for k in range(4):
            gax += g[k, 0]
            gay += g[k, 1]
            if g[k, 0] != 0.0 or g[k, 1] != 0.0:
                ma = min(ma, m[nod[k]])
            if nod[4 + k] >= 0 and (g[4 + k, 0] != 0.0 or g[4 + k, 1] != 0.0):
                mb = min(mb, m[nod[4 + k]])
        meff = ma if wall else effective_mass(ma, mb)
        # The law's parameters, normal traction and its tangent
        kn0 = law[lr, P_KN0]
        ks = law[lr, P_KS]
        mu = wall_mu[w] if wall else law[lr, P_MU]
        delta = area / length
        mt, kt, ed = normal_force(delta, 1.0, kn0, law[lr, P_DMAX], law[lr, P_RCAP])
        tn = -mt
        # Area change in this step (dA = sum g.du) and relative motion of the contact point
        da = 0.0
        rux = 0.0
        ruy = 0.0
        for k in range(NNOD):
            nd = nod[k]
            if nd < 0:
                continue
            da += g[k, 0] * du[nd, 0] + g[k, 1] * du[nd, 1]
            # B's part minus A's part of the contact point's increment
            sg = 1.0 if k >= 4 else -1.0
            rux += sg * wgt[k] * du[nd, 0]
            ruy += sg * wgt[k] * du[nd, 1]
        # Normal damping: a dashpot on the area rate, no tension in total
        t = tn
        if dt > 0.0:
            t = damped_traction(tn, kt, da / dt, meff, length, np.sqrt(gax * gax + gay * gay),
                                law[lr, P_ZETA])
        # Normal force on A along n, and the shear of the tangential increment
        fn = -t * max(gax * nx + gay * ny, 0.0)
        tx = -ny
        ty = nx
        if deep:
            # An element inside its body holds no shear, and the pair conducts no heat: the
            # grains' friction and conduction act through their boundary elements' pairs
            ks = 0.0
            width = 0.0
            us_new, fs, diss = 0.0, 0.0, 0.0
        else:
            us_new, fs, diss = shear_update(us, rux * tx + ruy * ty, length, ks, mu, fn)
        # Nodal forces -t dA/dx plus the shear at the contact point (+ on A, - on B), in the
        # caller's order (flip: the caller's A is our B)
        j = 4 if flip else 0
        for k in range(NNOD):
            sgs = fs if k < 4 else -fs
            o = (k + j) % NNOD
            nodes[r, o] = nod[k]
            weights[r, o] = wgt[k]
            fnod[r, o, 0] = -t * g[k, 0] + sgs * wgt[k] * tx
            fnod[r, o, 1] = -t * g[k, 1] + sgs * wgt[k] * ty
        sgn = -1.0 if flip else 1.0
        active[r] = C_ACTIVE
        us_out[r] = us_new
        res[r, R_FN] = fn
        res[r, R_FS] = fs
        res[r, R_ENERGY] = length * ed + 0.5 * ks * length * us_new * us_new
        res[r, R_DISS] = diss
        res[r, R_STIFF] = kt
        res[r, R_DELTA] = delta
        res[r, R_WIDTH] = width
        res[r, R_NX] = sgn * nx
        res[r, R_NY] = sgn * ny
        res[r, R_CX] = cx
        res[r, R_CY] = cy
        res[r, R_DAMP] = (t - tn) * da
        res[r, R_LEN] = length
        res[r, R_KSL] = ks * length
        res[r, R_MEFF] = meff
        res[r, R_AREA] = area
        if add:
            for o in range(NNOD):
                nd = nodes[r, o]
                if nd < 0 or nd >= n_owned:
                    continue
                fc[nd, 0] += fnod[r, o, 0]
                fc[nd, 1] += fnod[r, o, 1]
    return q, nbad, nev


def _dense_rows(n):
    """The key and element outputs contact_pass writes besides the caller's (dense: unused)."""
    return np.empty((n, 4), np.int64), np.empty((n, 2), np.int64)


def element_potentials(elen):
    """Corner and centroid values (edep, eapex) of elements that are each a body of their own:
    zero at the corners, half the contact length at the centroid (grain_depth)."""
    return np.zeros((elen.shape[0], 4)), 0.5 * np.asarray(elen, float)


def element_pair_forces(x, du, conn, ebnd, egid, eloc, elen, pairs, params, us_in, active, nodes,
                        weights, fnod, us_out, res, m, dt, depth=None):
    """Contact forces of the element pairs pairs (np, 2) (elements of different bodies), one
    output row per pair (contact_pass; C_NONE where they do not touch).

    params (np, NPAR) law parameters (contact_law.P_*); us_in (np,) shear history; depth the
    potential law's (edep, eapex) (default: element_potentials); the other inputs and the
    outputs as contact_pass. Returns the number of guarded contacts.
    """
    n = pairs.shape[0]
    keys, elems = _dense_rows(n)
    none = np.zeros((0, 2))
    edep, eapex = element_potentials(elen) if depth is None else depth
    return contact_pass(x, du, m, conn, ebnd, egid, eloc, elen, edep, eapex,
                        np.zeros(0, np.int64), params, 0, np.arange(n), none, none,
                        np.zeros(0), pairs.astype(np.int64),
                        np.zeros((0, 4), np.int64), np.zeros(0), us_in, True, False, dt,
                        np.empty((conn.shape[0], 4)), np.zeros((0, 2)), 0, active, keys,
                        elems, nodes, weights, fnod, us_out, res)[1]


def element_wall_forces(x, du, conn, ebnd, elen, elems, wall_p0, wall_n, params, us_in, active,
                        nodes, weights, fnod, us_out, res, m, dt):
    """Contact forces between elements elems (nw,) and rigid walls (increment zero), one output
    row per element (contact_pass): element i against the wall {p : n.(p - p0) < 0} with p0 =
    wall_p0[i] and n = wall_n[i] the unit normal out of the wall into the domain, the law
    params[i] (its friction the wall's). The normal from the element (A) into the wall (B) is
    -n; the pair's length is the element's elen; nodes[i, 4:] = -1, with no force or weight.
    Returns the number of guarded contacts.
    """
    n = elems.shape[0]
    keys, rows = _dense_rows(n)
    cand = np.stack([elems.astype(np.int64), -1 - np.arange(n)], axis=1)
    ids = np.zeros(conn.shape[0], np.int64)
    edep, eapex = element_potentials(elen)
    return contact_pass(x, du, m, conn, ebnd, ids, ids, elen, edep, eapex, ids, params, 0,
                        np.arange(n),
                        np.ascontiguousarray(wall_p0, float), np.ascontiguousarray(wall_n, float),
                        np.ascontiguousarray(params[:, P_MU]), cand,
                        np.zeros((0, 4), np.int64), np.zeros(0), us_in, True, False, dt,
                        np.empty((conn.shape[0], 4)), np.zeros((0, 2)), 0, active, keys,
                        rows, nodes, weights, fnod, us_out, res)[1]
