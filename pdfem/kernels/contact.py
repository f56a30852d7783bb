"""Element-to-element and element-to-wall contact forces (report sec. 5, figs. 4-7).

A contact is a pair of boundary elements of two different bodies. The kernels compute, for every
candidate pair, the overlap polygon, the contact frame, the normal and shear forces of the law in
contact_law.py and the equivalent nodal forces on one boundary edge of each element (fig. 7). They
never add into the global force array: ``contact_step.accumulate_sorted`` does that, in an order
the caller chooses (contacts sorted by global key), so that a node's force is the same sum on any
number of ranks.

Contact frame (the normal-direction rule). For the overlap polygon of A and B let N_A (N_B) be the
sum of (outward normal x length) of its edges lying on *grain-boundary* edges (ebnd = 1) of A (B).
The unit normal n is N_A - N_B normalised; it points from A into B. For the usual lens bounded by
one boundary edge of each element this is exactly the normal of the chord joining the two crossing
points (the rule of the report), but it stays exact for a flat contact whose overlap is cut by an
interior element edge, where the chord is a diagonal of the overlap and its normal is tilted by
about atan(delta/width). If N_A - N_B vanishes or makes an obtuse angle with the sum over all of
A's overlap edges (which points from A into B whatever the shape), that sum is used instead.
The contact width is the extent of the overlap along the tangent t = (-n_y, n_x), the mean
overlap is delta = area/width and the contact point c is the overlap centroid.

Orientation. Each pair is evaluated internally with the element of lower global key (egid, eloc)
as A, whatever order the caller gives, so both orders give bit-identical (mirrored) results and
the caller's orientation cannot change a bit. Outputs refer to the caller's order: pairs[p, 0] is
"A". The shear history u_s is invariant under the swap (t and the relative displacement both flip).

Output layout per contact p: active[p] (int8, codes C_*), nodes[p] = (a1, a2, b1, b2) (int64, the
boundary edge of A and of B; -1 for a wall), weights[p] = (1 - sA, sA, 1 - sB, sB), fa[p] = force on
A (on B it is -fa), nodal forces = +w_k fa on A's nodes, -w_k fa on B's; us_out[p] the new history;
res[p, :] the scalars R_*.
"""

import numpy as np
from numba import njit

from pdfem.kernels.contact_law import (
    P_DMAX,
    P_KN0,
    P_KS,
    P_MU,
    P_RCAP,
    P_ZETA,
    damped_normal,
    effective_mass,
    normal_force,
    shear_update,
)
from pdfem.kernels.overlap import (
    OV_NONE,
    OV_OK,
    OV_OVERFLOW,
    T_SRC,
    alloc_clip_buffers,
    element_corners,
    halfplane_overlap,
    quad_overlap_area,
)

# Columns of res[p, :]
R_FN = 0  # normal force, tension positive (<= 0) [N/m]
R_FS = 1  # shear force on A along t [N/m]
R_ENERGY = 2  # stored elastic energy, normal + shear [J/m]
R_DISS = 3  # frictional dissipation of this step [J/m]
R_STIFF = 4  # current tangent stiffness max(kn, ks w), for the time step [N/m^2]
R_DELTA = 5  # mean normal overlap delta = area/width [m]
R_WIDTH = 6  # contact width [m]
R_NX = 7  # unit normal from A (pairs[p, 0]) into B, x
R_NY = 8  # unit normal, y
R_CX = 9  # contact point (overlap centroid), x
R_CY = 10  # contact point, y
R_DAMP = 11  # dissipation of the normal damping in this step, (F_n - F_n elastic) dh [J/m]
NRES = 12

# Codes of active[p]; negative codes are guards the caller must treat as errors
C_NONE = 0  # no overlap: no force, history reset
C_ACTIVE = 1  # in contact
C_INSIDE = -1  # one element inside the other (or behind the wall): penetration too deep
C_NOEDGE = -2  # an element of the pair has no boundary edge
C_NONORMAL = -3  # the contact normal is undefined (symmetric overlap)
C_OVERFLOW = -4  # clip buffer overflow (cannot happen for convex quads)


@njit(cache=True)
def _pair_normal(ox, oy, otag, k, ebnd, a, b):
    """Unit normal from A into B from the boundary-edge normal sums (module docstring)."""
    nx = 0.0
    ny = 0.0
    ax = 0.0
    ay = 0.0
    for i in range(k):
        i1 = i + 1 if i + 1 < k else 0
        # Outward normal x length of the overlap edge i -> i+1
        ex = oy[i1] - oy[i]
        ey = ox[i] - ox[i1]
        src = otag[i, T_SRC]
        if src >= 0:
            ax += ex
            ay += ey
            if ebnd[a, src] != 0:
                nx += ex
                ny += ey
        elif ebnd[b, -1 - src] != 0:
            nx -= ex
            ny -= ey
    # Fall back on A's whole part of the overlap boundary (topologically from A into B)
    if nx * ax + ny * ay <= 0.0:
        nx = ax
        ny = ay
    r = np.sqrt(nx * nx + ny * ny)
    if r == 0.0:
        return 0.0, 0.0
    return nx / r, ny / r


@njit(cache=True)
def _width(ox, oy, k, tx, ty):
    """Extent of the overlap polygon along the unit tangent (tx, ty)."""
    lo = 0.0
    hi = 0.0
    # Coordinates relative to vertex 0 (the overlap is tiny next to |x|)
    for i in range(1, k):
        s = (ox[i] - ox[0]) * tx + (oy[i] - oy[0]) * ty
        lo = min(lo, s)
        hi = max(hi, s)
    return hi - lo


@njit(cache=True)
def _nearest_edge(xe, ebnd, e, cx, cy):
    """Boundary edge of element e nearest to c and the parameter s in [0, 1] of c's projection.

    Returns (edge, s); edge = -1 when e has no boundary edge. The lowest edge index wins ties.
    """
    best = np.inf
    kb = -1
    sb = 0.0
    for k in range(4):
        if ebnd[e, k] == 0:
            continue
        k1 = (k + 1) % 4
        dx = xe[k1, 0] - xe[k, 0]
        dy = xe[k1, 1] - xe[k, 1]
        s = ((cx - xe[k, 0]) * dx + (cy - xe[k, 1]) * dy) / (dx * dx + dy * dy)
        s = min(max(s, 0.0), 1.0)
        rx = xe[k, 0] + s * dx - cx
        ry = xe[k, 1] + s * dy - cy
        d2 = rx * rx + ry * ry
        if d2 < best:
            best = d2
            kb = k
            sb = s
    return kb, sb


@njit(cache=True)
def _edge_du(du, n1, n2, s):
    """Displacement increment at parameter s of the edge n1 -> n2 (shape functions 1 - s, s)."""
    return (1.0 - s) * du[n1, 0] + s * du[n2, 0], (1.0 - s) * du[n1, 1] + s * du[n2, 1]


@njit(cache=True)
def _clear(p, us_keep, active, nodes, weights, fa, us_out, res, code):
    """Outputs of a contact that applies no force (history kept for guards, reset otherwise)."""
    active[p] = code
    for k in range(4):
        nodes[p, k] = -1
        weights[p, k] = 0.0
    fa[p, 0] = 0.0
    fa[p, 1] = 0.0
    us_out[p] = us_keep
    for k in range(res.shape[1]):
        res[p, k] = 0.0


@njit(cache=True)
def _law(p, area, width, nx, ny, cx, cy, dus, us, params, fa, us_out, res, sg, dh, dt, meff):
    """Contact law at pair p with the parameters params[p] (indexed in place, no row view);
    writes fa (sign sg: -1 when the caller's A is our B) and res. dh: separation of the
    sides along n in this step of length dt; meff: their effective mass (normal damping)."""
    delta = area / width
    fe, kn, en = normal_force(delta, width, params[p, P_KN0], params[p, P_DMAX],
                              params[p, P_RCAP])
    fn = damped_normal(fe, kn, dh / dt if dt > 0.0 else 0.0, meff, params[p, P_ZETA])
    us_new, fs, diss = shear_update(us, dus, width, params[p, P_KS], params[p, P_MU], fn)
    # Force on A: normal (fn <= 0 pushes A back along -n) plus shear along t
    tx = -ny
    ty = nx
    fa[p, 0] = sg * (fn * nx + fs * tx)
    fa[p, 1] = sg * (fn * ny + fs * ty)
    us_out[p] = us_new
    res[p, R_FN] = fn
    res[p, R_FS] = fs
    res[p, R_ENERGY] = en + 0.5 * params[p, P_KS] * width * us_new * us_new
    res[p, R_DISS] = diss
    res[p, R_STIFF] = max(kn, params[p, P_KS] * width)
    res[p, R_DELTA] = delta
    res[p, R_WIDTH] = width
    res[p, R_NX] = sg * nx
    res[p, R_NY] = sg * ny
    res[p, R_CX] = cx
    res[p, R_CY] = cy
    res[p, R_DAMP] = (fn - fe) * dh


@njit(cache=True)
def element_pair_forces(
    x, du, conn, ebnd, egid, eloc, pairs, params, us_in, active, nodes, weights, fa, us_out, res,
    m, dt
):
    """Contact forces of the element pairs pairs (np, 2) (elements of different bodies).

    x, du (nn, 2): positions and displacement increments of the step (du / dt is the velocity
    the normal damping sees; dt = 0: none); m (nn,) lumped masses; conn (ne, 4) int64 CCW;
    ebnd (ne, 4) int8 boundary-edge flags; egid, eloc (ne,) int64 global element key; params
    (np, NPAR) law parameters (contact_law.P_*); us_in (np,) shear history. Outputs: see module
    docstring. Returns the number of guarded contacts (active < 0).
    """
    ox, oy, otag, wx, wy, wtag = alloc_clip_buffers()
    xa = np.empty((4, 2))
    xb = np.empty((4, 2))
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
        st, area, cx, cy, k = quad_overlap_area(xa, xb, ox, oy, otag, wx, wy, wtag)
        if st == OV_NONE:
            _clear(p, 0.0, active, nodes, weights, fa, us_out, res, C_NONE)
            continue
        if st != OV_OK:
            code = C_OVERFLOW if st == OV_OVERFLOW else C_INSIDE
            _clear(p, us_in[p], active, nodes, weights, fa, us_out, res, code)
            nbad += 1
            continue
        # Contact frame and the boundary edge of each side nearest to the contact point
        nx, ny = _pair_normal(ox, oy, otag, k, ebnd, a, b)
        ka, sa = _nearest_edge(xa, ebnd, a, cx, cy)
        kb, sb = _nearest_edge(xb, ebnd, b, cx, cy)
        if nx == 0.0 and ny == 0.0 or ka < 0 or kb < 0:
            code = C_NONORMAL if ka >= 0 and kb >= 0 else C_NOEDGE
            _clear(p, us_in[p], active, nodes, weights, fa, us_out, res, code)
            nbad += 1
            continue
        width = _width(ox, oy, k, -ny, nx)
        a1 = conn[a, ka]
        a2 = conn[a, (ka + 1) % 4]
        b1 = conn[b, kb]
        b2 = conn[b, (kb + 1) % 4]
        # Tangential relative displacement increment of B with respect to A at c
        dax, day = _edge_du(du, a1, a2, sa)
        dbx, dby = _edge_du(du, b1, b2, sb)
        dus = (dbx - dax) * -ny + (dby - day) * nx
        sg = -1.0 if flip else 1.0
        # Separation along n and effective mass of the two edges, for the damping
        dh = (dbx - dax) * nx + (dby - day) * ny
        meff = effective_mass(min(m[a1], m[a2]), min(m[b1], m[b2]))
        _law(p, area, width, nx, ny, cx, cy, dus, us_in[p], params, fa, us_out, res, sg, dh, dt,
             meff)
        # Nodal layout in the caller's order (a1, a2, b1, b2)
        active[p] = C_ACTIVE
        j = 2 if flip else 0
        nodes[p, j] = a1
        nodes[p, j + 1] = a2
        nodes[p, 2 - j] = b1
        nodes[p, 3 - j] = b2
        weights[p, j] = 1.0 - sa
        weights[p, j + 1] = sa
        weights[p, 2 - j] = 1.0 - sb
        weights[p, 3 - j] = sb
    return nbad


@njit(cache=True)
def element_wall_forces(
    x,
    du,
    conn,
    ebnd,
    elems,
    wall_p0,
    wall_n,
    params,
    us_in,
    active,
    nodes,
    weights,
    fa,
    us_out,
    res,
    m,
    dt,
):
    """Contact forces between elements elems (nw,) and rigid walls (increment zero).

    Wall i is the half-plane {p : n.(p - p0) < 0} with p0 = wall_p0[i] and n = wall_n[i] the unit
    normal out of the wall into the domain. The normal from the element (A) into the wall (B) is -n.
    Outputs as element_pair_forces with nodes[i, 2:] = -1 and weights[i, 2:] = 0; fa is the force
    on the element. Returns the number of guarded contacts.
    """
    ox, oy, otag, wx, wy, wtag = alloc_clip_buffers()
    xa = np.empty((4, 2))
    nbad = 0
    for p in range(elems.shape[0]):
        e = elems[p]
        element_corners(x, conn, e, xa)
        st, area, cx, cy, _, _, _, _, k = halfplane_overlap(
            xa, wall_p0[p], wall_n[p], ox, oy, otag, wx, wy, wtag
        )
        if st == OV_NONE:
            _clear(p, 0.0, active, nodes, weights, fa, us_out, res, C_NONE)
            continue
        ke, se = _nearest_edge(xa, ebnd, e, cx, cy)
        if st != OV_OK or ke < 0:
            code = C_NOEDGE if st == OV_OK else (C_OVERFLOW if st == OV_OVERFLOW else C_INSIDE)
            _clear(p, us_in[p], active, nodes, weights, fa, us_out, res, code)
            nbad += 1
            continue
        nx = -wall_n[p, 0]
        ny = -wall_n[p, 1]
        width = _width(ox, oy, k, -ny, nx)
        e1 = conn[e, ke]
        e2 = conn[e, (ke + 1) % 4]
        # Relative increment of the (fixed) wall with respect to the element, along t
        dax, day = _edge_du(du, e1, e2, se)
        dus = -dax * -ny - day * nx
        dh = -(dax * nx + day * ny)
        _law(p, area, width, nx, ny, cx, cy, dus, us_in[p], params, fa, us_out, res, 1.0, dh, dt,
             min(m[e1], m[e2]))
        active[p] = C_ACTIVE
        nodes[p, 0] = e1
        nodes[p, 1] = e2
        nodes[p, 2] = -1
        nodes[p, 3] = -1
        weights[p, 0] = 1.0 - se
        weights[p, 1] = se
        weights[p, 2] = 0.0
        weights[p, 3] = 0.0
    return nbad
