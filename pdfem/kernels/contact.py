"""Element-to-element and element-to-wall contact forces (report sec. 5, figs. 4-7).

A contact is a pair of boundary elements of two different bodies. The kernels compute, for every
candidate pair, the overlap polygon, the contact frame and the forces of the law in
contact_law.py on the nodes of both elements. They never add into the global force array:
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
"""

import numpy as np
from numba import njit

from pdfem.kernels.broad_phase import element_corners
from pdfem.kernels.contact_frame import (
    NNOD,
    alloc_overlap_work,
    area_gradient,
    loaded_mass,
    nearest_edge,
    overlap_extent,
    pair_overlap,
    side_sum,
)
from pdfem.kernels.contact_law import (
    P_DMAX,
    P_KN0,
    P_KS,
    P_MU,
    P_RCAP,
    P_ZETA,
    damped_traction,
    effective_mass,
    normal_force,
    shear_update,
)
from pdfem.kernels.overlap import (
    OV_NONE,
    OV_OK,
    OV_OVERFLOW,
    alloc_clip_buffers,
    halfplane_overlap,
)

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
def _clear(p, us_keep, active, nodes, weights, fnod, us_out, res, code):
    """Outputs of a contact that applies no force (history kept for guards, reset otherwise)."""
    active[p] = code
    for k in range(NNOD):
        nodes[p, k] = -1
        weights[p, k] = 0.0
        fnod[p, k, 0] = 0.0
        fnod[p, k, 1] = 0.0
    us_out[p] = us_keep
    for k in range(res.shape[1]):
        res[p, k] = 0.0


@njit(cache=True)
def _law(p, g, gax, gay, area, length, nx, ny, wgt, du, nod, us, params, res, dt, meff):
    """The contact law of pair p in canonical orientation: overwrites the area gradient g with
    the nodal forces and writes the law's columns of res. wgt (8,): contact-point weights; du,
    nod: increments and node ids of g's rows (-1: none); meff: effective mass of the sides.
    Returns the new shear history."""
    ks = params[p, P_KS]
    delta = area / length
    mt, kt, ed = normal_force(delta, 1.0, params[p, P_KN0], params[p, P_DMAX], params[p, P_RCAP])
    tn = -mt
    # Area change in this step (dA = sum g.du) and relative motion of the contact point
    da = 0.0
    rux = 0.0
    ruy = 0.0
    for r in range(NNOD):
        nd = nod[r]
        if nd < 0:
            continue
        da += g[r, 0] * du[nd, 0] + g[r, 1] * du[nd, 1]
        # B's part minus A's part of the contact point's increment
        sg = 1.0 if r >= 4 else -1.0
        rux += sg * wgt[r] * du[nd, 0]
        ruy += sg * wgt[r] * du[nd, 1]
    # Normal damping: a dashpot on the area rate, no tension in total
    t = tn
    if dt > 0.0:
        t = damped_traction(tn, kt, da / dt, meff, length, np.sqrt(gax * gax + gay * gay),
                            params[p, P_ZETA])
    # Normal force on A along n, and the shear of the tangential increment
    fn = -t * max(gax * nx + gay * ny, 0.0)
    tx = -ny
    ty = nx
    us_new, fs, diss = shear_update(us, rux * tx + ruy * ty, length, ks, params[p, P_MU], fn)
    # Nodal forces: -t dA/dx, plus the shear at the contact point (+ on A, - on B)
    for r in range(NNOD):
        sgs = fs if r < 4 else -fs
        g[r, 0] = -t * g[r, 0] + sgs * wgt[r] * tx
        g[r, 1] = -t * g[r, 1] + sgs * wgt[r] * ty
    res[p, R_FN] = fn
    res[p, R_FS] = fs
    res[p, R_ENERGY] = length * ed + 0.5 * ks * length * us_new * us_new
    res[p, R_DISS] = diss
    res[p, R_STIFF] = kt
    res[p, R_DELTA] = delta
    res[p, R_DAMP] = (t - tn) * da
    res[p, R_LEN] = length
    res[p, R_KSL] = ks * length
    res[p, R_MEFF] = meff
    res[p, R_AREA] = area
    return us_new


@njit(cache=True)
def _store(p, g, nod, wgt, flip, width, nx, ny, cx, cy, active, nodes, weights, fnod, res):
    """Outputs of active pair p in the caller's order (A's nodes first; flip: the caller's A is
    our B) and the frame columns of res."""
    j = 4 if flip else 0
    sg = -1.0 if flip else 1.0
    for r in range(NNOD):
        q = (r + j) % NNOD
        nodes[p, q] = nod[r]
        weights[p, q] = wgt[r]
        fnod[p, q, 0] = g[r, 0]
        fnod[p, q, 1] = g[r, 1]
    active[p] = C_ACTIVE
    res[p, R_WIDTH] = width
    res[p, R_NX] = sg * nx
    res[p, R_NY] = sg * ny
    res[p, R_CX] = cx
    res[p, R_CY] = cy


@njit(cache=True)
def element_pair_forces(
    x, du, conn, ebnd, egid, eloc, elen, pairs, params, us_in, active, nodes, weights, fnod,
    us_out, res, m, dt
):
    """Contact forces of the element pairs pairs (np, 2) (elements of different bodies).

    x, du (nn, 2): positions and displacement increments of the step (du / dt is the velocity
    the normal damping sees; dt = 0: none); m (nn,) lumped masses; conn (ne, 4) int64 CCW;
    ebnd (ne, 4) int8 boundary-edge flags; egid, eloc (ne,) int64 global element key; elen
    (ne,) contact lengths; params (np, NPAR) law parameters (contact_law.P_*); us_in (np,) shear
    history. Outputs (module docstring): active (np,), nodes (np, 8), weights (np, 8), fnod
    (np, 8, 2), us_out (np,), res (np, NRES). Returns the number of guarded contacts.
    """
    buf = alloc_clip_buffers()
    buf2 = alloc_clip_buffers()
    work = alloc_overlap_work()
    xa = np.empty((4, 2))
    xb = np.empty((4, 2))
    g = np.empty((NNOD, 2))
    acc = np.empty(4)
    wgt = np.empty(NNOD)
    nod = np.empty(NNOD, np.int64)
    nbad = 0
    for p in range(pairs.shape[0]):
        # Canonical orientation: A is the element of lower global key
        a = pairs[p, 0]
        b = pairs[p, 1]
        flip = egid[a] > egid[b] or (egid[a] == egid[b] and eloc[a] > eloc[b])
        if flip:
            a, b = b, a
        element_corners(x, conn, a, xa)
        element_corners(x, conn, b, xb)
        st, area, cx, cy, nx, ny, width = pair_overlap(xa, xb, ebnd, a, b, buf, buf2, work, g,
                                                       acc)
        if st == OV_NONE:
            _clear(p, 0.0, active, nodes, weights, fnod, us_out, res, C_NONE)
            continue
        if st != OV_OK:
            code = C_OVERFLOW if st == OV_OVERFLOW else C_INSIDE
            _clear(p, us_in[p], active, nodes, weights, fnod, us_out, res, code)
            nbad += 1
            continue
        # The boundary edge of each side nearest to the contact point
        ka, sa = nearest_edge(xa, ebnd, a, cx, cy)
        kb, sb = nearest_edge(xb, ebnd, b, cx, cy)
        length = min(elen[a], elen[b])
        if nx == 0.0 and ny == 0.0 or ka < 0 or kb < 0 or not length > 0.0:
            code = C_NONORMAL if ka >= 0 and kb >= 0 and length > 0.0 else C_NOEDGE
            _clear(p, us_in[p], active, nodes, weights, fnod, us_out, res, code)
            nbad += 1
            continue
        for r in range(4):
            nod[r] = conn[a, r]
            nod[4 + r] = conn[b, r]
            wgt[r] = 0.0
            wgt[4 + r] = 0.0
        wgt[ka] = 1.0 - sa
        wgt[(ka + 1) % 4] = sa
        wgt[4 + kb] = 1.0 - sb
        wgt[4 + (kb + 1) % 4] = sb
        gax, gay = side_sum(g, 0)
        meff = effective_mass(loaded_mass(g, nod, m, 0), loaded_mass(g, nod, m, 4))
        us_out[p] = _law(p, g, gax, gay, area, length, nx, ny, wgt, du, nod, us_in[p], params,
                         res, dt, meff)
        _store(p, g, nod, wgt, flip, width, nx, ny, cx, cy, active, nodes, weights, fnod, res)
    return nbad


@njit(cache=True)
def element_wall_forces(
    x, du, conn, ebnd, elen, elems, wall_p0, wall_n, params, us_in, active, nodes, weights, fnod,
    us_out, res, m, dt
):
    """Contact forces between elements elems (nw,) and rigid walls (increment zero).

    Wall i is the half-plane {p : n.(p - p0) < 0} with p0 = wall_p0[i] and n = wall_n[i] the unit
    normal out of the wall into the domain. The normal from the element (A) into the wall (B) is
    -n; the pair's length is the element's elen. Outputs as element_pair_forces with nodes[i,
    4:] = -1 and no force or weight there. Returns the number of guarded contacts.
    """
    ox, oy, otag, wx, wy, wtag = alloc_clip_buffers()
    xa = np.empty((4, 2))
    xw = np.empty((0, 2))
    qw = np.zeros(1, np.int64)
    g = np.empty((NNOD, 2))
    lohi = np.empty(2)
    wgt = np.zeros(NNOD)
    nod = np.full(NNOD, -1, np.int64)
    nbad = 0
    for p in range(elems.shape[0]):
        e = elems[p]
        element_corners(x, conn, e, xa)
        st, area, cx, cy, _, _, _, _, k = halfplane_overlap(
            xa, wall_p0[p], wall_n[p], ox, oy, otag, wx, wy, wtag
        )
        if st == OV_NONE:
            _clear(p, 0.0, active, nodes, weights, fnod, us_out, res, C_NONE)
            continue
        ke, se = nearest_edge(xa, ebnd, e, cx, cy)
        if st != OV_OK or ke < 0 or not elen[e] > 0.0:
            code = C_NOEDGE if st == OV_OK else (C_OVERFLOW if st == OV_OVERFLOW else C_INSIDE)
            _clear(p, us_in[p], active, nodes, weights, fnod, us_out, res, code)
            nbad += 1
            continue
        nx = -wall_n[p, 0]
        ny = -wall_n[p, 1]
        for r in range(4):
            nod[r] = conn[e, r]
            wgt[r] = 0.0
        wgt[ke] = 1.0 - se
        wgt[(ke + 1) % 4] = se
        g[:, :] = 0.0
        area_gradient(ox, oy, otag, k, xa, xw, qw, g)
        gax, gay = side_sum(g, 0)
        us_out[p] = _law(p, g, gax, gay, area, elen[e], nx, ny, wgt, du, nod, us_in[p], params,
                         res, dt, loaded_mass(g, nod, m, 0))
        lohi[:] = 0.0
        overlap_extent(ox, oy, k, -ny, nx, ox[0], oy[0], lohi)
        _store(p, g, nod, wgt, False, lohi[1] - lohi[0], nx, ny, cx, cy, active, nodes, weights,
               fnod, res)
    return nbad
