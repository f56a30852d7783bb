"""The 1-point quad with hourglass control (plane strain, thickness 1 m): stress and forces.

The objective update of pdfem.kernels.element (mid-step gradient, Cayley rotation, material
update, forces at the current configuration) at the element centre, with the mean (=
centroid) gradient b_I = dN_I/dx, b_x = (y24, y31, y42, y13)/(2A), b_y = (x42, x13, x24,
x31)/(2A), plus total-form stiffness hourglass control: the Flanagan-Belytschko (1981) hourglass
vector of h = (1, -1, 1, -1), taken once in the configuration the run starts from (area A0),
    gamma_I = (h_I - (h.X) b_xI - (h.Y) b_yI) / 4     (gamma.h = 1, gamma . linear = 0)
measures the hourglass mode of the current positions, q_a = sum_I gamma_I x_Ia (zero for
every affine map of the starting element, rigid motion included; summed over the corners'
positions relative to corner 0, with gamma_0 = -(gamma_1 + gamma_2 + gamma_3) so that the
forces add up to zero and q does not lose digits to the grain's distance from the origin).
The mode holds the energy
    E = k (q.q) / 2,   k = hg_coef A0 (b0.b0) M(eta),   eta = 1 - A/A0,
with b0 the starting mean gradients and M a modulus of the element's material at its
compression, K(eta) its bulk modulus (K0 with a linear bulk, the tangent of the Hugoniot,
pdfem.kernels.eos, with an equation of state) and G its shear modulus:
- HG_COEFFICIENT: M = K(eta) + 4G/3, scaled by the scene's coefficient hg_coef;
- HG_BENDING: M = (2/3) E', E' = 4G (3K(eta) + G)/(3K(eta) + 4G), hg_coef = 1: the element's
  own bending stiffness. For a rectangle of sides 2a x 2b moved in its hourglass mode
  (u = q xi eta), the continuum bends: the strain of the mode in x is q eta/a, and with no
  shear and the stress across free (plane strain) it holds (A/3) E' q_x^2/(2 a^2) (Belytschko
  & Bindeman 1991, the assumed strain that makes the element exact in bending). The two modes
  of the rectangle cost k_x = (4/3) E' b/a and k_y = (4/3) E' a/b; their mean is the spring's
  k = (2/3) E' A (b.b) (A (b.b) = a/b + b/a), exact for a square and, for an elongated element,
  stiffer in its soft mode, as the 2 x 2 rule is. E' stays below 4G however stiff the bulk:
  bending changes no volume;
- HG_FULL: M = (2/3)(K(eta) + 7G/3), hg_coef = 1: the stiffness the 2 x 2 rule gives the
  mode (its mean over the two modes of a rectangle, as above);
- HG_POINTS: not a spring but the energy of pdfem.kernels.hourglass_points, the 2 x 2 rule's
  elastic energy of the element's departure from its mean deformation at every amplitude,
  which grows without bound as a corner closes (hg then has HG_COLS_POINTS columns, the last
  six the starting offsets of corners 1-3 from corner 0); its forces are its exact gradient.
The spring stiffens with the element as the Flanagan-Belytschko spring does. The
nodal forces are the gradient of E (internal, subtracted from f),
    f_Ia = k q_a gamma_I + (q.q / 2) dk/dA A b_Ia,   dk/dA = -hg_coef (b0.b0) dM/deta,
which add up to zero, have no moment and do no work beyond E's change, whatever the strain or
rotation; that change, E(x) - E(x - du), joins ewint. M comes from the material's own row
(no temperature softening), so E is a function of the positions alone. hg[e] = (gamma_0..3,
hg_coef A0 (b0.b0), A0), from :func:`hourglass_reference`; hg of shape (0, HG_COLS) switches
hourglass control off.

One kernel for every material and thermal coupling: every quantity of an element lives in
scalar locals (no scratch arrays), which lets LLVM keep them in registers. A cap point takes
the elastic trial and its yield value exactly as ``cap.cap_update`` computes them and calls
the plastic return only when the trial is outside; an elastic point takes the elastic
increment. With thermal coupling (eth of shape (ne, 3)) the material row may be softened
with the element temperature and the thermal strain is taken out of the material's strain
(pdfem.kernels.element.thermal_row); a material with an equation of state takes the secant
bulk modulus of the step along its Hugoniot (pdfem.kernels.eos). Sign convention: tension positive.
"""

import math

import numpy as np
from numba import njit

from pdfem.kernels.cap import plastic_update
from pdfem.kernels.cap_surface import yield_value
from pdfem.kernels.elastic import elastic_increment
from pdfem.kernels.element import element_viscosity, thermal_row
from pdfem.kernels.eos import eos_row, gruneisen_heat, gruneisen_row
from pdfem.kernels.hourglass_points import points_eval, start_data
from pdfem.kernels.params import BULK, CAP, ELASTIC, EOS_G, EOS_S, MODEL, SHEAR

# Columns of an element's hourglass reference: gamma_0..3, hg_coef A0 (b0.b0), A0; with the
# points stiffness also the starting offsets of corners 1-3 from corner 0 (x1, y1, x2, y2, x3, y3)
HG_COLS = 6
HG_COLS_POINTS = 12
# The hourglass stiffness (module docstring): three spring moduli and the points energy
HG_COEFFICIENT = 0
HG_BENDING = 1
HG_FULL = 2
HG_POINTS = 3


@njit(cache=True)
def _area(x0, y0, x1, y1, x2, y2, x3, y3):
    """Area of a quad (half the cross product of its diagonals)."""
    return 0.5 * ((x2 - x0) * (y3 - y1) - (x3 - x1) * (y2 - y0))


@njit(cache=True)
def _tangent_bulk(p, eta):
    """(K, dK/deta): the Hugoniot's tangent bulk modulus of the material row p at compression
    eta (pdfem.kernels.eos; eos_s > 0 and eta > 0), else K0 and 0 (inf past the Hugoniot's
    limit 1 - s eta = 0)."""
    k0, s = p[BULK], p[EOS_S]
    if not (s > 0.0 and eta > 0.0):
        return k0, 0.0
    # K = K0 u v: u = (1 - eta)(1 + s eta), v = (1 - s eta)^-3
    g = 1.0 - s * eta
    if not g > 0.0:
        return math.inf, math.inf
    u = (1.0 - eta) * (1.0 + s * eta)
    v = 1.0 / (g * g * g)
    du = (s - 1.0) - 2.0 * s * eta
    return k0 * u * v, k0 * (du * v + u * 3.0 * s * v / g)


@njit(cache=True)
def hourglass_modulus(p, eta, model):
    """(M, dM/deta) of the module docstring for the material row p at compression eta, K the
    tangent bulk modulus (_tangent_bulk): M = K + 4G/3 for HG_COEFFICIENT, M = (2/3) E' with
    E' = 4G (3K + G)/(3K + 4G) (plane-strain bending, E' -> 4G as K -> inf) for HG_BENDING."""
    k, dk = _tangent_bulk(p, eta)
    g = p[SHEAR]
    if model == HG_BENDING:
        if k == math.inf:
            return 8.0 * g / 3.0, 0.0
        r = 1.0 / (3.0 * k + 4.0 * g)
        return 8.0 * g * (3.0 * k + g) * r / 3.0, 24.0 * g * g * r * r * dk
    if model == HG_FULL:
        return 2.0 * (k + 7.0 * g / 3.0) / 3.0, 2.0 * dk / 3.0
    return k + 4.0 * g / 3.0, dk


@njit(cache=True)
def _mean_gradient(x0, y0, x1, y1, x2, y2, x3, y3):
    """Area and Flanagan-Belytschko mean gradients (bx0..bx3, by0..by3) of a quad (b unset
    (zero) when the area is not positive)."""
    a = _area(x0, y0, x1, y1, x2, y2, x3, y3)
    if a <= 0.0:
        return a, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0
    r = 1.0 / (2.0 * a)
    return (a, (y1 - y3) * r, (y2 - y0) * r, (y3 - y1) * r, (y0 - y2) * r,
            (x3 - x1) * r, (x0 - x2) * r, (x1 - x3) * r, (x2 - x0) * r)


@njit(cache=True)
def _gamma(x0, y0, x1, y1, x2, y2, x3, y3, bx0, bx1, bx2, bx3, by0, by1, by2, by3):
    """Hourglass vector (g0..g3) for h = (1, -1, 1, -1)."""
    hx = 1.0 * x0 + -1.0 * x1 + 1.0 * x2 + -1.0 * x3
    hy = 1.0 * y0 + -1.0 * y1 + 1.0 * y2 + -1.0 * y3
    return (0.25 * (1.0 - hx * bx0 - hy * by0), 0.25 * (-1.0 - hx * bx1 - hy * by1),
            0.25 * (1.0 - hx * bx2 - hy * by2), 0.25 * (-1.0 - hx * bx3 - hy * by3))


@njit(cache=True)
def q4_forces_1pt(x, du, conn, emat, mat_params, sig, mst, hg, hg_model, e0, e1, f, ewint, ewp,
                  eth, dt=0.0, qv=None):
    """One-point quads with total-form hourglass control (hg, with the stiffness hg_model:
    HG_COEFFICIENT, HG_BENDING, HG_FULL or HG_POINTS, module docstring) on elements [e0, e1).

    Updates sig (ne,1,4) and mst (ne,1,nst) in place, subtracts the internal
    forces from f (nn,2) element by element, adds stress and hourglass work to ewint and
    plastic work to ewp. eth (ne, 3) couples temperature in (element.thermal_row; the
    thermal-strain work goes to eth[:, 2]); shape (0, 3) or None leaves it out, None in a
    version compiled without the thermal branches (the solver's call without coupling).
    dt is the step's duration, used only by a rate-dependent cap (relaxation time > 0).
    qv (ne,), the elements' bulk viscosity of the last step, heats the points of a material
    with a Gruneisen coefficient (element.q4_forces_2x2); None or shape (0,): no viscosity.
    Returns -1, or the first element with a non-positive (mid-step or current) area, a
    non-finite cap input, a failed cap return or an unknown material model.
    """
    if sig.shape[1] != 1:
        raise ValueError("q4_forces_1pt needs sig of shape (ne, 1, 4)")
    if hg_model == HG_POINTS and hg.shape[0] > 0 and hg.shape[1] < HG_COLS_POINTS:
        raise ValueError("the points hourglass stiffness needs hg of shape (ne, 12)")
    has_hg = hg.shape[0] > 0
    pbuf = np.empty(mat_params.shape[1])
    ebuf = np.empty(mat_params.shape[1])
    hbuf = np.empty(8)
    for e in range(e0, e1):
        # The material's own row (the hourglass spring's) and the step's (softened, EOS)
        row = mat_params[emat[e]]
        p = row
        dth = 0.0
        # eth None: numba compiles this kernel without the thermal branches (dth stays 0.0)
        if eth is not None:
            if eth.shape[0] > 0:
                p, dth = thermal_row(p, eth, e, True, pbuf)
        # Current coordinates, increments and mid-step coordinates of the 4 nodes
        n0 = conn[e, 0]
        n1 = conn[e, 1]
        n2 = conn[e, 2]
        n3 = conn[e, 3]
        x0, y0, u0, v0 = x[n0, 0], x[n0, 1], du[n0, 0], du[n0, 1]
        x1, y1, u1, v1 = x[n1, 0], x[n1, 1], du[n1, 0], du[n1, 1]
        x2, y2, u2, v2 = x[n2, 0], x[n2, 1], du[n2, 0], du[n2, 1]
        x3, y3, u3, v3 = x[n3, 0], x[n3, 1], du[n3, 0], du[n3, 1]
        m0, l0 = x0 - 0.5 * u0, y0 - 0.5 * v0
        m1, l1 = x1 - 0.5 * u1, y1 - 0.5 * v1
        m2, l2 = x2 - 0.5 * u2, y2 - 0.5 * v2
        m3, l3 = x3 - 0.5 * u3, y3 - 0.5 * v3
        # Strain and spin increment from the mid-step mean gradient
        am, bx0, bx1, bx2, bx3, by0, by1, by2, by3 = _mean_gradient(m0, l0, m1, l1, m2, l2,
                                                                    m3, l3)
        if am <= 0.0:
            return e
        gxx = u0 * bx0 + u1 * bx1 + u2 * bx2 + u3 * bx3
        gxy = u0 * by0 + u1 * by1 + u2 * by2 + u3 * by3
        gyx = v0 * bx0 + v1 * bx1 + v2 * bx2 + v3 * bx3
        gyy = v0 * by0 + v1 * by1 + v2 * by2 + v3 * by3
        w = 0.5 * (gxy - gyx)
        d = 1.0 / (1.0 + 0.25 * w * w)
        c = (1.0 - 0.25 * w * w) * d
        sn = w * d
        # Rotate the stress (Cayley), update it, trapezoidal work density
        s = sig[e, 0]
        sxx, syy, sxy = s[0], s[1], s[2]
        r0 = c * c * sxx + 2.0 * c * sn * sxy + sn * sn * syy
        r1 = sn * sn * sxx - 2.0 * c * sn * sxy + c * c * syy
        r2 = c * sn * (syy - sxx) + (c * c - sn * sn) * sxy
        r3 = s[3]
        d0, d1, d2, d3 = gxx - dth, gyy - dth, 0.5 * (gxy + gyx), -dth
        # A material with an equation of state: its bulk modulus over the step
        jmid = 1.0
        dq = 0.0
        if p[EOS_S] > 0.0:
            if p[EOS_G] > 0.0:
                ste = mst[e, 0]
                p, jmid, dq = gruneisen_row(p, r0, r1, r3, d0 + d1 + d3, ste[ste.shape[0] - 1],
                                            element_viscosity(qv, e), ebuf)
            else:
                p = eos_row(p, r0, r1, r3, d0 + d1 + d3, ebuf)
        dwp = 0.0
        model = int(p[MODEL])
        if model == CAP:
            # Cap: the elastic trial and its yield value as cap.cap_update computes them
            st = mst[e, 0]
            if not (math.isfinite(d0 + d1 + d2 + d3)
                    and math.isfinite(r0 + r1 + r2 + r3 + st[0])):
                return e
            g2 = 2.0 * p[SHEAR]
            lam = p[BULK] - g2 / 3.0
            dv = d0 + d1 + d3
            t0, t1 = r0 + (lam * dv + g2 * d0), r1 + (lam * dv + g2 * d1)
            t2, t3 = r2 + g2 * d2, r3 + (lam * dv + g2 * d3)
            i1t = t0 + t1 + t3
            mm = i1t / 3.0
            jt = math.sqrt(0.5 * ((t0 - mm) ** 2 + (t1 - mm) ** 2 + (t3 - mm) ** 2) + t2 * t2)
            over = yield_value(p, i1t, jt, st[0])
            if over <= 0.0:
                s[0], s[1], s[2], s[3] = t0, t1, t2, t3
            else:
                # Outside: the plastic return from the rotated stress
                s[0], s[1], s[2], s[3] = r0, r1, r2, r3
                status, dwp = plastic_update(p, s, st, d0, d1, d2, d3, over, dt)
                if status != 0:
                    return e
                t0, t1, t2, t3 = s[0], s[1], s[2], s[3]
        elif model == ELASTIC:
            i0, i1, i2, i3 = elastic_increment(p, d0, d1, d2, d3)
            t0, t1, t2, t3 = r0 + i0, r1 + i1, r2 + i2, r3 + i3
            s[0], s[1], s[2], s[3] = t0, t1, t2, t3
        else:
            return e
        wk = 0.5 * ((r0 + t0) * d0 + (r1 + t1) * d1 + 2.0 * (r2 + t2) * d2 + (r3 + t3) * d3)
        # A Mie-Gruneisen point: the step's energy, the deviatoric work's pressure
        if p[EOS_G] > 0.0:
            gruneisen_heat(p, s, (r0 + r1 + r3) / 3.0, wk, d0 + d1 + d3, jmid, dq, mst[e, 0])
            t0, t1, t3 = s[0], s[1], s[3]
        wth = 0.5 * dth * (r0 + t0 + r1 + t1 + r3 + t3)
        # Current geometry: area and gradients for the forces
        a, bx0, bx1, bx2, bx3, by0, by1, by2, by3 = _mean_gradient(x0, y0, x1, y1, x2, y2,
                                                                   x3, y3)
        if a <= 0.0:
            return e
        ewint[e] += wk * a
        ewp[e] += dwp * a
        if eth is not None:
            if eth.shape[0] > 0:
                eth[e, 2] += wth * a
        # Stress divergence forces f_I = A sig . b_I
        fx0, fy0 = a * (t0 * bx0 + t2 * by0), a * (t2 * bx0 + t1 * by0)
        fx1, fy1 = a * (t0 * bx1 + t2 * by1), a * (t2 * bx1 + t1 * by1)
        fx2, fy2 = a * (t0 * bx2 + t2 * by2), a * (t2 * bx2 + t1 * by2)
        fx3, fy3 = a * (t0 * bx3 + t2 * by3), a * (t2 * bx3 + t1 * by3)
        # Hourglass: the mode q of the current positions, its energy's change, its forces
        if has_hg and hg_model == HG_POINTS:
            a0 = hg[e, 5]
            k, dk = _tangent_bulk(row, 1.0 - a / a0)
            ko, _ = _tangent_bulk(row, 1.0 - _area(x0 - u0, y0 - v0, x1 - u1, y1 - v1, x2 - u2,
                                                   y2 - v2, x3 - u3, y3 - v3) / a0)
            mu = row[SHEAR]
            # The energy at the last positions (no gradient) and now (with its forces)
            start = start_data(hg[e, 6], hg[e, 7], hg[e, 8], hg[e, 9], hg[e, 10], hg[e, 11])
            eo, _, ok = points_eval(start, (x1 - u1) - (x0 - u0), (y1 - v1) - (y0 - v0),
                                    (x2 - u2) - (x0 - u0), (y2 - v2) - (y0 - v0),
                                    (x3 - u3) - (x0 - u0), (y3 - v3) - (y0 - v0),
                                    ko - 2.0 * mu / 3.0, mu, hbuf, False)
            en, s2, ok2 = points_eval(start, x1 - x0, y1 - y0, x2 - x0, y2 - y0, x3 - x0,
                                      y3 - y0, k - 2.0 * mu / 3.0, mu, hbuf, True)
            if not (ok and ok2):
                return e
            ewint[e] += en - eo
            c = -s2 * dk * a / a0
            fx0, fy0 = fx0 + hbuf[0] + c * bx0, fy0 + hbuf[1] + c * by0
            fx1, fy1 = fx1 + hbuf[2] + c * bx1, fy1 + hbuf[3] + c * by1
            fx2, fy2 = fx2 + hbuf[4] + c * bx2, fy2 + hbuf[5] + c * by2
            fx3, fy3 = fx3 + hbuf[6] + c * bx3, fy3 + hbuf[7] + c * by3
        elif has_hg:
            g0, g1, g2, g3, kr, a0 = hg[e, 0], hg[e, 1], hg[e, 2], hg[e, 3], hg[e, 4], hg[e, 5]
            q0 = g1 * (x1 - x0) + g2 * (x2 - x0) + g3 * (x3 - x0)
            q1 = g1 * (y1 - y0) + g2 * (y2 - y0) + g3 * (y3 - y0)
            p0 = q0 - (g1 * (u1 - u0) + g2 * (u2 - u0) + g3 * (u3 - u0))
            p1 = q1 - (g1 * (v1 - v0) + g2 * (v2 - v0) + g3 * (v3 - v0))
            qq = q0 * q0 + q1 * q1
            if row[EOS_S] > 0.0:
                # The spring stiffens with compression: its modulus now and at the last
                # positions, and dE/dA along the area gradient A b_I
                m, dm = hourglass_modulus(row, 1.0 - a / a0, hg_model)
                mo, _ = hourglass_modulus(row, 1.0 - _area(x0 - u0, y0 - v0, x1 - u1, y1 - v1,
                                                           x2 - u2, y2 - v2, x3 - u3,
                                                           y3 - v3) / a0, hg_model)
                c = -0.5 * qq * kr * dm * a / a0
                fx0, fy0 = fx0 + c * bx0, fy0 + c * by0
                fx1, fy1 = fx1 + c * bx1, fy1 + c * by1
                fx2, fy2 = fx2 + c * bx2, fy2 + c * by2
                fx3, fy3 = fx3 + c * bx3, fy3 + c * by3
            else:
                m, _ = hourglass_modulus(row, 0.0, hg_model)
                mo = m
            ewint[e] += 0.5 * kr * (m * qq - mo * (p0 * p0 + p1 * p1))
            h0, h1 = kr * m * q0, kr * m * q1
            fx0, fy0 = fx0 + h0 * g0, fy0 + h1 * g0
            fx1, fy1 = fx1 + h0 * g1, fy1 + h1 * g1
            fx2, fy2 = fx2 + h0 * g2, fy2 + h1 * g2
            fx3, fy3 = fx3 + h0 * g3, fy3 + h1 * g3
        # f -= fe, node by node
        f[n0, 0] -= fx0
        f[n0, 1] -= fy0
        f[n1, 0] -= fx1
        f[n1, 1] -= fy1
        f[n2, 0] -= fx2
        f[n2, 1] -= fy2
        f[n3, 0] -= fx3
        f[n3, 1] -= fy3
    return -1


@njit(cache=True)
def hourglass_reference(x, conn, hg_coef, e0, e1, hg):
    """hg[e] = (gamma_0..3, hg_coef A (b.b), A) of elements [e0, e1) in the configuration x
    (module docstring): the hourglass vector orthogonal to every linear field of that
    configuration, the spring's geometric factor and the area (zero factor for an element
    whose area is not positive, which the first force evaluation stops on)."""
    for e in range(e0, e1):
        n0, n1, n2, n3 = conn[e, 0], conn[e, 1], conn[e, 2], conn[e, 3]
        x0, y0, x1, y1 = x[n0, 0], x[n0, 1], x[n1, 0], x[n1, 1]
        x2, y2, x3, y3 = x[n2, 0], x[n2, 1], x[n3, 0], x[n3, 1]
        a, bx0, bx1, bx2, bx3, by0, by1, by2, by3 = _mean_gradient(x0, y0, x1, y1, x2, y2,
                                                                   x3, y3)
        _, g1, g2, g3 = _gamma(x0, y0, x1, y1, x2, y2, x3, y3, bx0, bx1, bx2, bx3, by0, by1,
                               by2, by3)
        hg[e, 0], hg[e, 1], hg[e, 2], hg[e, 3] = -(g1 + g2 + g3), g1, g2, g3
        bb = (bx0 * bx0 + by0 * by0 + bx1 * bx1 + by1 * by1 + bx2 * bx2 + by2 * by2
              + bx3 * bx3 + by3 * by3)
        hg[e, 4] = hg_coef * max(a, 0.0) * bb
        hg[e, 5] = a
        if hg.shape[1] >= HG_COLS_POINTS:
            hg[e, 6], hg[e, 7], hg[e, 8], hg[e, 9] = x1 - x0, y1 - y0, x2 - x0, y2 - y0
            hg[e, 10], hg[e, 11] = x3 - x0, y3 - y0
