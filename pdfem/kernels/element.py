"""Updated Lagrangian 4-node quad (plane strain, thickness 1 m): stress update and forces.

Objective update (Hughes & Winget 1980) per integration point, with du = x_{n+1} - x_n:
    L = d du / d x_mid evaluated at x_mid = x - du/2,
    deps = sym(L), dw = skew(L), Q = (I - dw/2)^-1 (I + dw/2)  (Cayley, exactly orthogonal),
    sig <- Q sig Q^T  (sigma_zz unchanged), then sig <- material_update(sig, deps),
and the internal forces use B at the current configuration x. A rigid rotation makes L exactly
skew at x_mid, so it rotates the stress and adds none.

Node order is counter-clockwise; natural coordinates of nodes 1..4 are (-1,-1), (1,-1), (1,1),
(-1,1). The 2x2 rule numbers its points in the same order at (+-1/sqrt3, +-1/sqrt3), weight 1.

The 1-point rule with hourglass control is pdfem.kernels.element_1pt.

Force kernels return -1 on success, else the index of the first element whose area / IP
Jacobian (mid-step or current) is not positive or whose material update failed; they stop
there, leaving that element partly updated (the run must then abort).
"""

import numpy as np
from numba import njit

from pdfem.kernels.eos import eos_row, gruneisen_heat, gruneisen_row
from pdfem.kernels.material import material_update, softened
from pdfem.kernels.params import ALPHA, EOS_G, EOS_S, SOFT_K, SOFT_Y

GP = 0.5773502691896257  # 1/sqrt(3), 2x2 Gauss abscissa
XI = np.array([-1.0, 1.0, 1.0, -1.0])  # natural coordinates of the nodes
ETA = np.array([-1.0, -1.0, 1.0, 1.0])


@njit(cache=True)
def _gather(x, du, conn, e, xc, xm, ue):
    """Current coordinates xc, mid-step coordinates xm and increments ue of element e."""
    for i in range(4):
        n = conn[e, i]
        for k in range(2):
            xc[i, k] = x[n, k]
            ue[i, k] = du[n, k]
            xm[i, k] = x[n, k] - 0.5 * du[n, k]


@njit(cache=True)
def _bvec(xe, bx, by):
    """Centroid gradients bx, by (4,) of a quad; returns its area (bx, by unset if <= 0)."""
    # Area from the cross product of the diagonals
    a = 0.5 * ((xe[2, 0] - xe[0, 0]) * (xe[3, 1] - xe[1, 1])
               - (xe[3, 0] - xe[1, 0]) * (xe[2, 1] - xe[0, 1]))
    if a <= 0.0:
        return a
    # Flanagan-Belytschko mean gradient
    r = 1.0 / (2.0 * a)
    for i in range(4):
        ip = (i + 1) % 4
        im = (i + 3) % 4
        bx[i] = (xe[ip, 1] - xe[im, 1]) * r
        by[i] = (xe[im, 0] - xe[ip, 0]) * r
    return a


@njit(cache=True)
def _ip_grad(xe, xi, eta, dx, dy):
    """Shape function gradients dx, dy (4,) at (xi, eta); returns det J (dx, dy unset if <= 0)."""
    # Jacobian of the isoparametric map
    j11 = 0.0
    j12 = 0.0
    j21 = 0.0
    j22 = 0.0
    for i in range(4):
        dxi = 0.25 * XI[i] * (1.0 + ETA[i] * eta)
        deta = 0.25 * ETA[i] * (1.0 + XI[i] * xi)
        j11 += dxi * xe[i, 0]
        j12 += deta * xe[i, 0]
        j21 += dxi * xe[i, 1]
        j22 += deta * xe[i, 1]
    det = j11 * j22 - j12 * j21
    if det <= 0.0:
        return det
    # Chain rule through the inverse Jacobian
    r = 1.0 / det
    for i in range(4):
        dxi = 0.25 * XI[i] * (1.0 + ETA[i] * eta)
        deta = 0.25 * ETA[i] * (1.0 + XI[i] * xi)
        dx[i] = (j22 * dxi - j21 * deta) * r
        dy[i] = (j11 * deta - j12 * dxi) * r
    return det


@njit(cache=True)
def _cayley(w):
    """(c, s) of Q = [[c, s], [-s, c]] = (I - W/2)^-1 (I + W/2), W = [[0, w], [-w, 0]]."""
    d = 1.0 / (1.0 + 0.25 * w * w)
    return (1.0 - 0.25 * w * w) * d, w * d


@njit(cache=True)
def _grad(ue, dx, dy):
    """Gradient of the increment (L_xx, L_xy, L_yx, L_yy), L_ab = d du_a / d x_b."""
    gxx = 0.0
    gxy = 0.0
    gyx = 0.0
    gyy = 0.0
    for i in range(4):
        gxx += ue[i, 0] * dx[i]
        gxy += ue[i, 0] * dy[i]
        gyx += ue[i, 1] * dx[i]
        gyy += ue[i, 1] * dy[i]
    return gxx, gxy, gyx, gyy


@njit(cache=True)
def _stress_point(p, s, st, gxx, gxy, gyx, gyy, c, sn, dth, deps, sold, ebuf, dt, q=0.0):
    """Objective update of one point stress s (4,).

    (gxx, gxy, gyx, gyy) is the mid-step gradient of du, (c, sn) the Cayley rotation of its
    skew part, dth the isotropic thermal strain increment (removed from the material's
    strain, sigma_zz included); ebuf receives the row of a material with an equation of
    state (eos.eos_row, eos.gruneisen_row); dt is the step's duration (a rate-dependent
    cap's); q the bulk viscosity of the element (heats a Mie-Gruneisen point, whose energy
    is the last value of st). Returns (status, dwp, mechanical work density, thermal-strain
    work density sigma:deps_th).
    """
    # Rotate the stress, Q sig Q^T with Q = [[c, sn], [-sn, c]]
    sxx = s[0]
    syy = s[1]
    sxy = s[2]
    s[0] = c * c * sxx + 2.0 * c * sn * sxy + sn * sn * syy
    s[1] = sn * sn * sxx - 2.0 * c * sn * sxy + c * c * syy
    s[2] = c * sn * (syy - sxx) + (c * c - sn * sn) * sxy
    # Material update with the symmetric part (plane strain)
    deps[0] = gxx - dth
    deps[1] = gyy - dth
    deps[2] = 0.5 * (gxy + gyx)
    deps[3] = -dth
    for k in range(4):
        sold[k] = s[k]
    dv = deps[0] + deps[1] + deps[3]
    jmid = 1.0
    dq = 0.0
    if p[EOS_S] > 0.0:
        if p[EOS_G] > 0.0:
            p, jmid, dq = gruneisen_row(p, s[0], s[1], s[3], dv, st[st.shape[0] - 1], q, ebuf)
        else:
            p = eos_row(p, s[0], s[1], s[3], dv, ebuf)
    status, dwp = material_update(p, s, deps, st, dt)
    # Stress power density, trapezoidal in time
    w = 0.5 * ((sold[0] + s[0]) * deps[0] + (sold[1] + s[1]) * deps[1]
               + 2.0 * (sold[2] + s[2]) * deps[2] + (sold[3] + s[3]) * deps[3])
    # A Mie-Gruneisen point: the step's energy, the deviatoric work's pressure
    if p[EOS_G] > 0.0 and status == 0:
        gruneisen_heat(p, s, (sold[0] + sold[1] + sold[3]) / 3.0, w, dv, jmid, dq, st)
    wth = 0.5 * dth * (sold[0] + s[0] + sold[1] + s[1] + sold[3] + s[3])
    return status, dwp, w, wth


@njit(cache=True)
def thermal_row(p, eth, e, has_th, pbuf):
    """Parameter row and thermal strain increment of element e.

    eth[e] = (mean temperature increment of the step, mean temperature, accumulated
    thermal-strain work sigma:deps_th [J/m]). The thermal strain increment is
    p[ALPHA] eth[e, 0]; a material with softening coefficients gets its row at eth[e, 1]
    (material.softened, into pbuf). Without coupling: (p, 0.0).
    """
    if not has_th:
        return p, 0.0
    dth = p[ALPHA] * eth[e, 0]
    if p[SOFT_K] != 0.0 or p[SOFT_Y] != 0.0:
        softened(p, eth[e, 1], pbuf)
        return pbuf, dth
    return p, dth


@njit(cache=True)
def element_viscosity(qv, e):
    """The bulk viscosity of element e from the last step (qv None or empty: 0)."""
    if qv is not None:
        if qv.shape[0] > 0:
            return qv[e]
    return 0.0


@njit(cache=True)
def _scatter(conn, e, fe, f):
    """f -= fe for the 4 nodes of element e, in node order."""
    for i in range(4):
        n = conn[e, i]
        f[n, 0] -= fe[i, 0]
        f[n, 1] -= fe[i, 1]


@njit(cache=True)
def unloaded_at_rest(du, conn, sig, eth, e, has_th):
    """Element e has not moved this step (du zero at its four nodes), carries no stress at any
    point and no temperature change: its update would leave its stress, state and work as
    they are and add zero force (the cap and elastic updates of a zero increment from zero
    stress are elastic and exact; the cap's parameter checks keep zero stress inside; a
    Mie-Gruneisen point's energy gains neither work nor viscous heat)."""
    if has_th and eth[e, 0] != 0.0:
        return False
    for i in range(4):
        n = conn[e, i]
        if du[n, 0] != 0.0 or du[n, 1] != 0.0:
            return False
    for ip in range(sig.shape[1]):
        for k in range(4):
            if sig[e, ip, k] != 0.0:
                return False
    return True


@njit(cache=True)
def q4_forces_2x2(x, du, conn, emat, mat_params, sig, mstate, hg, hg_model, e0, e1,
                  f, ewint, ewp, eth, rest=None, dt=0.0, qv=None):
    """Fully integrated (2x2 Gauss) quads on elements [e0, e1); hg and hg_model are ignored.

    Updates sig (ne,4,4) and mstate per point; subtracts internal forces from f element by
    element; adds stress work to ewint and plastic work to ewp (weights x current det J).
    eth (ne, 3) couples temperature in (see thermal_row); shape (0, 3) leaves it out.
    rest, an int64 array (1,), skips the elements unloaded at rest (unloaded_at_rest) and adds
    their count to rest[0]; None (the default) computes every element. dt is the step's
    duration, used only by a rate-dependent cap (relaxation time > 0; 0: elastic there).
    qv (ne,), the elements' bulk viscosity of the last step, heats the points of a material
    with a Gruneisen coefficient; None or shape (0,): no viscosity.
    Returns -1, or the first element with a non-positive IP Jacobian or a failed material.
    """
    if sig.shape[1] != 4:
        raise ValueError("q4_forces_2x2 needs sig of shape (ne, 4, 4)")
    # Scratch buffers, allocated once per call
    xc = np.empty((4, 2))
    xm = np.empty((4, 2))
    ue = np.empty((4, 2))
    fe = np.empty((4, 2))
    dx = np.empty(4)
    dy = np.empty(4)
    deps = np.empty(4)
    sold = np.empty(4)
    nost = np.zeros(0)
    pbuf = np.empty(mat_params.shape[1])
    ebuf = np.empty(mat_params.shape[1])
    has_state = mstate.shape[0] > 0
    has_th = eth.shape[0] > 0
    for e in range(e0, e1):
        # An element at rest and unloaded: computing it would change nothing
        if rest is not None and unloaded_at_rest(du, conn, sig, eth, e, has_th):
            rest[0] += 1
            continue
        p, dth = thermal_row(mat_params[emat[e]], eth, e, has_th, pbuf)
        q = element_viscosity(qv, e)
        _gather(x, du, conn, e, xc, xm, ue)
        for i in range(4):
            fe[i, 0] = 0.0
            fe[i, 1] = 0.0
        for ip in range(4):
            xi = GP * XI[ip]
            eta = GP * ETA[ip]
            # Stress update with the mid-step gradients at this point
            if _ip_grad(xm, xi, eta, dx, dy) <= 0.0:
                return e
            gxx, gxy, gyx, gyy = _grad(ue, dx, dy)
            c, sn = _cayley(0.5 * (gxy - gyx))
            s = sig[e, ip]
            if has_state:
                status, dwp, w, wth = _stress_point(p, s, mstate[e, ip], gxx, gxy, gyx, gyy,
                                                    c, sn, dth, deps, sold, ebuf, dt, q)
            else:
                status, dwp, w, wth = _stress_point(p, s, nost, gxx, gxy, gyx, gyy, c, sn,
                                                    dth, deps, sold, ebuf, dt)
            if status != 0:
                return e
            # Forces and work with the current gradients and volume
            dv = _ip_grad(xc, xi, eta, dx, dy)
            if dv <= 0.0:
                return e
            ewint[e] += w * dv
            ewp[e] += dwp * dv
            if has_th:
                eth[e, 2] += wth * dv
            for i in range(4):
                fe[i, 0] += dv * (s[0] * dx[i] + s[2] * dy[i])
                fe[i, 1] += dv * (s[2] * dx[i] + s[1] * dy[i])
        _scatter(conn, e, fe, f)
    return -1
