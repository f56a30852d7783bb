"""The potential contact law: an overlap measure that keeps growing up to full overlap.

The report's law (contact.py) takes its mean overlap from the overlap area A of two elements.
Once one element lies wholly inside the other, A is that element's own area and no longer
changes with position, so the force, dE/dx = t_n dA/dx, vanishes: nothing pushes the element
back out. The potential law (``contact.law = "potential"``) measures the overlap instead by the
integral of a potential over it, as the combined finite-discrete element method does:

    W = int_{A cap B} (psi_A + psi_B) dx                                  [m^3 per m]

psi_E, the potential over element E, is the field of E's body (grain_depth): linear on each of
E's four triangles (corner k, corner k+1, centroid c_E, the corners' mean), with the values
d_k at the corners (the corners' depth below the body's boundary, zero on it) and h_E at the
centroid. An element that is a body of its own (all corners on its boundary) has psi zero on
its edges and h_E = elen_E / 2 at its centroid: for a square of side s exactly the distance to
the nearest edge. A body's elements carry its depth, so a node that crosses the boundary
elements into the inside elements keeps meeting a potential that rises towards the body's
middle; the pairs of a boundary element with any element of the other body are candidates.
Against a wall, the element's own potential (zero at its corners) and the wall's, the depth
behind its line:

    W = int_{A cap H} (psi_A + d) dx,     d(x) = -n . (x - p0)  (H: behind the wall).

Behind a wall d rises without bound, and inside a body psi rises towards its middle, so W
grows and dW/dx is nonzero at any penetration short of the exact symmetric overlap of two
coincident elements, or an element centred on a body's deepest point.

The law of contact_law then acts on the mean overlap delta = sqrt(W / L), with L the pair's
length (contact.py). Two squares of side s pressed together over a whole edge by d have
W = s d^2 (1 - d / (3 s)): delta = d to leading order, the area law's delta = A / L = d. The
contact kernel works with the equivalent area A_eq = L delta = sqrt(W L) and its gradient
dA_eq/dx = dW/dx / (2 delta), so the traction, the energy E = L phi(delta), the damping, the
stable step and every output keep their meaning: the forces are -t_n dA_eq/dx = -dE/dx, the
gradient of an energy, and do no work beyond its change.

dW/dx is exact. For one term I = int_{S cap T} psi_T (S an element, T a triangle of the other
element Q):
- moving Q's nodes changes the field at a fixed point: with barycentric coordinates lambda_j
  of T's vertices p_j (v0, v1, c_Q), psi_T = sum_j v_j lambda_j and d psi_T / d p_j =
  -lambda_j grad psi_T; c_Q is the mean of Q's corners, so each corner takes a quarter of c_Q's
  part. The integrand is linear, so the integral is the clipped polygon's area times its value
  at the polygon's centroid;
- moving Q's nodes also sweeps the domain's edges that lie on Q's outer edges, which carry
  psi_T (nonzero where Q's corners lie inside their body): node i of the edge (i, i+1) gets
  int psi_T N_i n ds. The domain's edges on the triangles' inner edges cancel between
  neighbours (the same psi and the same motion);
- moving S's nodes sweeps the domain along the polygon's edges on S's boundary: node i of the
  edge (i, i+1) gets int psi_T N_i n ds, psi_T and the hat N_i both linear along the edge.
Triangles of non-positive orientation (a corner pushed past the element's centroid) hold no
potential. Then the inner edges they share with their positive neighbours no longer cancel, and
the domain's edges on them carry the term of the host's motion sweeping them, as S's edges do.

Sign: W >= 0; g receives +dW/dx (the energy's gradient; the force is its negative).
"""

import numpy as np
from numba import njit

from pdfem.kernels.overlap import (
    T_SRC,
    clip_halfplane,
    clip_into,
    load_subject,
    polygon_area_centroid,
)

# Rows of a pair's gradient g (8, 2): A's nodes 0-3, B's nodes 4-7
ROW_A = 0
ROW_B = 4


@njit(cache=True)
def element_triangle(xq, k, tri):
    """Triangle k of the quad xq (4, 2): corners k, k+1 and the centroid, into tri (3, 2).
    Returns twice its signed area (positive when counter-clockwise)."""
    k1 = k + 1 if k + 1 < 4 else 0
    tri[0, 0] = xq[k, 0]
    tri[0, 1] = xq[k, 1]
    tri[1, 0] = xq[k1, 0]
    tri[1, 1] = xq[k1, 1]
    tri[2, 0] = 0.25 * (xq[0, 0] + xq[1, 0] + xq[2, 0] + xq[3, 0])
    tri[2, 1] = 0.25 * (xq[0, 1] + xq[1, 1] + xq[2, 1] + xq[3, 1])
    return ((tri[1, 0] - tri[0, 0]) * (tri[2, 1] - tri[0, 1])
            - (tri[1, 1] - tri[0, 1]) * (tri[2, 0] - tri[0, 0]))


@njit(cache=True)
def apex_coordinate(tri, d2, x, y):
    """Barycentric coordinate of the apex tri[2] at (x, y); d2 twice the triangle's area."""
    ex = tri[1, 0] - tri[0, 0]
    ey = tri[1, 1] - tri[0, 1]
    return (ex * (y - tri[0, 1]) - ey * (x - tri[0, 0])) / d2


@njit(cache=True)
def field_gradient(tri, d2, k, v0, v1, vc, area, cx, cy, g, rq):
    """Add to g rows rq..rq+3 the derivative of int psi_T over a polygon of this area and
    centroid (cx, cy) with respect to the nodes of the quad whose triangle k tri is (the field
    moving under a fixed polygon); psi_T takes the values v0, v1, vc at tri's vertices (corner
    k, corner k + 1, centroid). Returns psi_T at the centroid."""
    # Barycentric coordinates at the centroid
    lc = apex_coordinate(tri, d2, cx, cy)
    l0 = ((tri[1, 0] - cx) * (tri[2, 1] - cy) - (tri[1, 1] - cy) * (tri[2, 0] - cx)) / d2
    l1 = 1.0 - l0 - lc
    # grad psi_T = sum_i v_i grad lambda_i, scaled by -area
    fx, fy, _ = linear_field(tri, d2, v0, v1, vc)
    gx = -area * fx
    gy = -area * fy
    k1 = k + 1 if k + 1 < 4 else 0
    g[rq + k, 0] += l0 * gx
    g[rq + k, 1] += l0 * gy
    g[rq + k1, 0] += l1 * gx
    g[rq + k1, 1] += l1 * gy
    # The centroid is the corners' mean
    for m in range(4):
        g[rq + m, 0] += 0.25 * lc * gx
        g[rq + m, 1] += 0.25 * lc * gy
    return v0 * l0 + v1 * l1 + vc * lc


@njit(cache=True)
def linear_field(tri, d2, v0, v1, vc):
    """(fx, fy, f0) of the linear field f0 + fx x + fy y taking the values v0, v1, vc at the
    vertices of tri (d2 twice its area)."""
    fx = 0.0
    fy = 0.0
    f0 = 0.0
    for i, v in ((0, v0), (1, v1), (2, vc)):
        if v == 0.0:
            continue
        j = i + 1 if i < 2 else 0
        m = j + 1 if j < 2 else 0
        # lambda_i = (x_j y_m - x_m y_j + (y_j - y_m) x + (x_m - x_j) y) / d2
        fx += v * (tri[j, 1] - tri[m, 1]) / d2
        fy += v * (tri[m, 0] - tri[j, 0]) / d2
        f0 += v * (tri[j, 0] * tri[m, 1] - tri[m, 0] * tri[j, 1]) / d2
    return fx, fy, f0


@njit(cache=True)
def edge_hat_moments(xi, yi, xj, yj, fx, fy, f0, fz, ax, ay, bx, by):
    """For the polygon edge (xi, yi) -> (xj, yj) lying on the element edge a -> b: its outward
    normal x length (ex, ey) and int f N ds / length for the hats of a (1 - s) and b (s),
    f = fz (f0 + fx x + fy y) linear along the edge. Returns (ok, ex, ey, ca, cb); ok is False
    for a degenerate a -> b, which moves no polygon edge."""
    ex = yj - yi
    ey = xi - xj
    fa = fz * (f0 + fx * xi + fy * yi)
    fb = fz * (f0 + fx * xj + fy * yj)
    # The ends' parameters along a -> b
    dx = bx - ax
    dy = by - ay
    ll = dx * dx + dy * dy
    if not ll > 0.0:
        return False, ex, ey, 0.0, 0.0
    sa = min(max(((xi - ax) * dx + (yi - ay) * dy) / ll, 0.0), 1.0)
    sb = min(max(((xj - ax) * dx + (yj - ay) * dy) / ll, 0.0), 1.0)
    ra = 1.0 - sa
    rb = 1.0 - sb
    ca = fa * ra / 3.0 + (fa * rb + fb * ra) / 6.0 + fb * rb / 3.0
    cb = fa * sa / 3.0 + (fa * sb + fb * sa) / 6.0 + fb * sb / 3.0
    return True, ex, ey, ca, cb


@njit(cache=True)
def sweep_gradient(xs, px, py, pt, n, fx, fy, f0, fz, g, rs):
    """Add to g rows rs..rs+3 the derivative of int f over the polygon in slot 0 (n vertices)
    with respect to the nodes of the subject xs whose edges its T_SRC >= 0 edges lie on; f is
    the linear field f0 + fx x + fy y, scaled by fz (fz = 0 adds nothing)."""
    if fz == 0.0:
        return
    for i in range(n):
        src = pt[0, i, T_SRC]
        if src < 0:
            continue
        i1 = i + 1 if i + 1 < n else 0
        # The polygon edge on the subject's edge src -> src + 1
        j = src
        j1 = j + 1 if j + 1 < 4 else 0
        ok, ex, ey, cj, cj1 = edge_hat_moments(px[0, i], py[0, i], px[0, i1], py[0, i1], fx,
                                               fy, f0, fz, xs[j, 0], xs[j, 1], xs[j1, 0],
                                               xs[j1, 1])
        if not ok:
            continue
        g[rs + j, 0] += cj * ex
        g[rs + j, 1] += cj * ey
        g[rs + j1, 0] += cj1 * ex
        g[rs + j1, 1] += cj1 * ey


@njit(cache=True)
def folded_triangles(xq, tri):
    """Bit k set when triangle k of the quad xq (element_triangle) holds no potential."""
    bits = 0
    for k in range(4):
        if not element_triangle(xq, k, tri) > 0.0:
            bits |= 1 << k
    return bits


@njit(cache=True)
def neighbour_bits(k):
    """Bits of the triangles sharing an inner edge with triangle k: k + 1 across its edge
    (corner k + 1, centroid), k - 1 across (centroid, corner k)."""
    return (1 << ((k + 1) & 3)) | (1 << ((k + 3) & 3))


@njit(cache=True)
def retag_subject_edges(pt, n):
    """Tags of a triangle clipped as the subject by a half-plane (slot 0, n vertices): its
    edge i becomes clip line i (T_SRC = -1 - i) and the half-plane's line -4, as clip_into
    tags a subject clipped by the triangle, for host_edge_gradient."""
    for i in range(n):
        src = pt[0, i, T_SRC]
        pt[0, i, T_SRC] = -1 - src if src >= 0 else -4


@njit(cache=True)
def host_edge_gradient(tri, k, folded, outer, px, py, pt, n, fx, fy, f0, fz, g, rq):
    """Add to g rows rq..rq+3 the sweep of the polygon in slot 0 along the host's edges that
    carry a potential no neighbour cancels: the inner edges of the host's triangle k (tri;
    clip line 1: corner k + 1 -> centroid, 2: centroid -> corner k) whose neighbour across is
    folded (bits of folded_triangles), and with outer its outer edge (clip line 0: corner k ->
    corner k + 1). The field is fz (f0 + fx x + fy y); the centroid's share goes a quarter to
    each corner."""
    k1 = (k + 1) & 3
    for i in range(n):
        line = -1 - pt[0, i, T_SRC]
        if line == 0:
            if not outer:
                continue
            a, b = 0, 1
        elif line == 1:
            if not folded & (1 << k1):
                continue
            a, b = 1, 2
        elif line == 2:
            if not folded & (1 << ((k + 3) & 3)):
                continue
            a, b = 2, 0
        else:
            continue
        i1 = i + 1 if i + 1 < n else 0
        # The polygon edge on the triangle's edge a -> b
        ok, ex, ey, ca, cb = edge_hat_moments(px[0, i], py[0, i], px[0, i1], py[0, i1], fx, fy,
                                              f0, fz, tri[a, 0], tri[a, 1], tri[b, 0], tri[b, 1])
        if not ok:
            continue
        # Triangle vertex 0 is corner k, 1 corner k + 1, 2 the centroid (the corners' mean)
        for v, cv in ((a, ca), (b, cb)):
            if v == 2:
                for m in range(4):
                    g[rq + m, 0] += 0.25 * cv * ex
                    g[rq + m, 1] += 0.25 * cv * ey
            else:
                r = rq + (k if v == 0 else k1)
                g[r, 0] += cv * ex
                g[r, 1] += cv * ey


@njit(cache=True)
def side_potential(xs, xq, dq, cq, px, py, pt, tri, g, rs, rq):
    """int over S cap Q of psi_Q (S = xs, Q = xq, both (4, 2) CCW; psi_Q takes the values dq
    (4,) at Q's corners and cq at its centroid), its gradient added to g: S's nodes in rows
    rs..rs+3, Q's in rows rq..rq+3. px, py, pt: clip buffers (slots 0 and 1 are used); tri
    (3, 2) scratch. Returns the integral (>= 0)."""
    w = 0.0
    folded = folded_triangles(xq, tri)
    for k in range(4):
        d2 = element_triangle(xq, k, tri)
        if not d2 > 0.0:
            continue
        n = clip_into(xs, 4, tri, 3, px, py, pt, 0)
        if n < 3:
            continue
        area, cx, cy = polygon_area_centroid(px, py, 0, n)
        if not area > 0.0:
            continue
        k1 = k + 1 if k + 1 < 4 else 0
        w += area * field_gradient(tri, d2, k, dq[k], dq[k1], cq, area, cx, cy, g, rq)
        # psi_T, linear on the triangle: S's edges sweep it
        fx, fy, f0 = linear_field(tri, d2, dq[k], dq[k1], cq)
        sweep_gradient(xs, px, py, pt, n, fx, fy, f0, 1.0, g, rs)
        # Q's edges carrying a potential no neighbour of the pair cancels: the outer edge
        # where its corners hold one, the inner edges next to a folded triangle
        outer = dq[k] != 0.0 or dq[k1] != 0.0
        if outer or folded & neighbour_bits(k):
            host_edge_gradient(tri, k, folded, outer, px, py, pt, n, fx, fy, f0, 1.0, g, rq)
    return w


@njit(cache=True)
def pair_potential(xa, xb, da, ca, db, cb, px, py, pt, tri, g):
    """W of elements A (xa) and B (xb) with potentials of corner values da, db (4,) and centroid
    values ca, cb; g (8, 2) is zeroed and receives dW/dx (A's nodes rows 0-3, B's rows 4-7).
    Returns W."""
    for r in range(8):
        g[r, 0] = 0.0
        g[r, 1] = 0.0
    w = side_potential(xa, xb, db, cb, px, py, pt, tri, g, ROW_A, ROW_B)
    return w + side_potential(xb, xa, da, ca, px, py, pt, tri, g, ROW_B, ROW_A)


@njit(cache=True)
def wall_potential(xa, ha, p0x, p0y, nx, ny, px, py, pt, tri, g):
    """W of element A (xa, its own potential zero at its corners and ha at its centroid) and
    the wall {p : n.(p - p0) < 0} (n its unit normal into the domain); g (8, 2) is zeroed and
    receives dW/dx in rows 0-3. Returns W."""
    for r in range(8):
        g[r, 0] = 0.0
        g[r, 1] = 0.0
    w = 0.0
    # A's own potential behind the wall: each triangle clipped by the wall's line (field only:
    # the polygons' edges lie on the wall, on A's boundary where psi = 0, or inside A)
    folded = folded_triangles(xa, tri)
    for k in range(4):
        d2 = element_triangle(xa, k, tri)
        if not d2 > 0.0:
            continue
        load_subject(tri, 3, px, py, pt, 1)
        n = clip_halfplane(px, py, pt, 1, 3, p0x, p0y, nx, ny, 0, 0)
        if n < 3:
            continue
        area, cx, cy = polygon_area_centroid(px, py, 0, n)
        if not area > 0.0:
            continue
        w += area * field_gradient(tri, d2, k, 0.0, 0.0, ha, area, cx, cy, g, ROW_A)
        # The inner edges whose neighbour holds no potential: here the polygon's edges keep
        # the subject's tags (the triangle's edge i), not clip-line tags
        if folded & neighbour_bits(k):
            fx, fy, f0 = linear_field(tri, d2, 0.0, 0.0, ha)
            retag_subject_edges(pt, n)
            host_edge_gradient(tri, k, folded, False, px, py, pt, n, fx, fy, f0, 1.0, g, ROW_A)
    # The wall's depth over the part of A behind it (A's edges sweep it)
    load_subject(xa, 4, px, py, pt, 1)
    n = clip_halfplane(px, py, pt, 1, 4, p0x, p0y, nx, ny, 0, 0)
    if n >= 3:
        area, cx, cy = polygon_area_centroid(px, py, 0, n)
        if area > 0.0:
            w += area * -(nx * (cx - p0x) + ny * (cy - p0y))
            sweep_gradient(xa, px, py, pt, n, -nx, -ny, nx * p0x + ny * p0y, 1.0, g, ROW_A)
    return w


@njit(cache=True)
def corner_extent(xq, tx, ty):
    """Extent of the corners of xq (4, 2) along (tx, ty)."""
    lo = np.inf
    hi = -np.inf
    for k in range(4):
        f = xq[k, 0] * tx + xq[k, 1] * ty
        lo = min(lo, f)
        hi = max(hi, f)
    return hi - lo


@njit(cache=True)
def corner_box(xq, tx, ty):
    """Box of the corners of xq (4, 2), (x_lo, x_hi, y_lo, y_hi), and their extent along
    (tx, ty)."""
    lx = hx = xq[0, 0]
    ly = hy = xq[0, 1]
    lo = hi = xq[0, 0] * tx + xq[0, 1] * ty
    for k in range(1, 4):
        lx = min(lx, xq[k, 0])
        hx = max(hx, xq[k, 0])
        ly = min(ly, xq[k, 1])
        hy = max(hy, xq[k, 1])
        f = xq[k, 0] * tx + xq[k, 1] * ty
        lo = min(lo, f)
        hi = max(hi, f)
    return lx, hx, ly, hy, hi - lo
