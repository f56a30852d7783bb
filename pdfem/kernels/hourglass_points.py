"""The 1-point rule's hourglass energy taken at the 2 x 2 Gauss points (the ``points`` stiffness
of pdfem.kernels.element_1pt): the deviation of each point's deformation from the centroid's,
stored as a hyperelastic energy. Plane strain, thickness 1 m; energies in J/m, tension positive.

With the starting corners X_I (their offsets from corner 0, which are all the energy needs), the
starting mean gradients b0_I and, at each Gauss point g (xi, eta = +-1/sqrt(3)), the starting
gradients grad_X N_I(g) and weight w_g = det J0(g) (the point's share of the starting area),
    F_c = sum_I x_I (x) b0_I,  F_g = sum_I x_I (x) grad_X N_I(g),  H_g = F_g F_c^-1,
    E = sum_g w_g Psi(H_g),  Psi(H) = mu/2 (H:H - 2 - 2 ln J) + lam/2 (ln J)^2,  J = det H.
H_g is the identity for every affine map of the starting element (rigid motion included), and
Psi is isotropic, so E is objective and zero unless the element leaves its starting shape. For
small deviations Psi is the linear-elastic energy with lam = K - 2G/3 and mu = G, and since the
weighted point gradients sum to the mean one (sum_g w_g grad_X N_I(g) = A0 b0_I), E is then the
2 x 2 rule's elastic energy of the element less that of its mean strain. Unlike a spring in the
hourglass mode, it grows without bound as a point's J falls to zero: a corner that closes costs
ever more energy. The gradient of E is exact:
    dE/dx_I = sum_g w_g [(P F_c^-T) grad_X N_I(g) - (H^T P F_c^-T) b0_I],
    P = dPsi/dH = mu (H - H^-T) + lam ln J H^-T.
"""

import math

from numba import njit

GP = 1.0 / math.sqrt(3.0)


@njit(cache=True)
def _outer(ax, ay, bx, by):
    """The 2 x 2 tensor sum_I a_I (x) b_I, row by row (11, 12, 21, 22)."""
    s11 = s12 = s21 = s22 = 0.0
    for i in range(4):
        s11 += ax[i] * bx[i]
        s12 += ax[i] * by[i]
        s21 += ay[i] * bx[i]
        s22 += ay[i] * by[i]
    return s11, s12, s21, s22


@njit(cache=True)
def _start_mean_gradients(rx, ry):
    """The starting mean gradients (b0x, b0y) of the corners (offsets rx, ry from corner 0)."""
    a0 = 0.5 * ((rx[2] - rx[0]) * (ry[3] - ry[1]) - (rx[3] - rx[1]) * (ry[2] - ry[0]))
    rr = 1.0 / (2.0 * a0)
    b0x = ((ry[1] - ry[3]) * rr, (ry[2] - ry[0]) * rr, (ry[3] - ry[1]) * rr, (ry[0] - ry[2]) * rr)
    b0y = ((rx[3] - rx[1]) * rr, (rx[0] - rx[2]) * rr, (rx[1] - rx[3]) * rr, (rx[2] - rx[0]) * rr)
    return b0x, b0y


@njit(cache=True)
def _start_point(rx, ry, xi, et):
    """Weight det J0 and starting gradients (gx, gy) of the corners at the point (xi, et)."""
    dnx = (-0.25 * (1 - et), 0.25 * (1 - et), 0.25 * (1 + et), -0.25 * (1 + et))
    dne = (-0.25 * (1 - xi), -0.25 * (1 + xi), 0.25 * (1 + xi), 0.25 * (1 - xi))
    j11, j12, j21, j22 = _outer(rx, ry, dnx, dne)
    w = j11 * j22 - j12 * j21
    gx = ((j22 * dnx[0] - j21 * dne[0]) / w, (j22 * dnx[1] - j21 * dne[1]) / w,
          (j22 * dnx[2] - j21 * dne[2]) / w, (j22 * dnx[3] - j21 * dne[3]) / w)
    gy = ((j11 * dne[0] - j12 * dnx[0]) / w, (j11 * dne[1] - j12 * dnx[1]) / w,
          (j11 * dne[2] - j12 * dnx[2]) / w, (j11 * dne[3] - j12 * dnx[3]) / w)
    return w, gx, gy


@njit(cache=True)
def start_data(r1x, r1y, r2x, r2y, r3x, r3y):
    """What the energy needs of the starting element, from the offsets r_I = X_I - X_0 of
    corners 1-3: the mean gradients (b0x, b0y) and, at each Gauss point, its weight and its
    corners' gradients (w, gx, gy: four of each, point by point)."""
    rx = (0.0, r1x, r2x, r3x)
    ry = (0.0, r1y, r2y, r3y)
    b0x, b0y = _start_mean_gradients(rx, ry)
    w0, gx0, gy0 = _start_point(rx, ry, -GP, -GP)
    w1, gx1, gy1 = _start_point(rx, ry, GP, -GP)
    w2, gx2, gy2 = _start_point(rx, ry, GP, GP)
    w3, gx3, gy3 = _start_point(rx, ry, -GP, GP)
    return b0x, b0y, (w0, w1, w2, w3), (gx0, gx1, gx2, gx3), (gy0, gy1, gy2, gy3)


@njit(cache=True)
def points_energy(r1x, r1y, r2x, r2y, r3x, r3y, c1x, c1y, c2x, c2y, c3x, c3y, lam, mu, out):
    """(E, S2, ok) of one element (module docstring) from the starting offsets r_I = X_I - X_0
    and the current offsets c_I = x_I - x_0 of corners 1-3, with the moduli lam and mu;
    out[2I], out[2I+1] = dE/dx_I for the corners 0-3 (they add up to zero). S2 = dE/dlam =
    sum_g w_g (ln J_g)^2 / 2. ok is False (E, S2 and out unset) when F_c or a point's H is not
    positive."""
    return points_eval(start_data(r1x, r1y, r2x, r2y, r3x, r3y), c1x, c1y, c2x, c2y, c3x, c3y,
                       lam, mu, out, True)


@njit(cache=True)
def points_eval(start, c1x, c1y, c2x, c2y, c3x, c3y, lam, mu, out, grad):
    """:func:`points_energy` from the element's :func:`start_data`; with ``grad`` False only
    (E, S2, ok), out untouched (the energy at the last positions, whose change the step
    books)."""
    b0x, b0y, ws, gxs, gys = start
    cx = (0.0, c1x, c2x, c3x)
    cy = (0.0, c1y, c2y, c3y)
    # F_c and its inverse
    f11, f12, f21, f22 = _outer(cx, cy, b0x, b0y)
    dc = f11 * f22 - f12 * f21
    if not dc > 0.0:
        return 0.0, 0.0, False
    i11, i12, i21, i22 = f22 / dc, -f12 / dc, -f21 / dc, f11 / dc
    if grad:
        for k in range(8):
            out[k] = 0.0
    e = 0.0
    s2 = 0.0
    for gp in range(4):
        # The point's starting weight and gradients
        w, gx, gy = ws[gp], gxs[gp], gys[gp]
        # F_g and H = F_g F_c^-1; the point's energy and S2
        g11, g12, g21, g22 = _outer(cx, cy, gx, gy)
        h11 = g11 * i11 + g12 * i21
        h12 = g11 * i12 + g12 * i22
        h21 = g21 * i11 + g22 * i21
        h22 = g21 * i12 + g22 * i22
        jj = h11 * h22 - h12 * h21
        if not jj > 0.0:
            return 0.0, 0.0, False
        lj = math.log(jj)
        e += w * (0.5 * mu * (h11 * h11 + h12 * h12 + h21 * h21 + h22 * h22 - 2.0 - 2.0 * lj)
                  + 0.5 * lam * lj * lj)
        s2 += w * 0.5 * lj * lj
        if not grad:
            continue
        # P = mu (H - H^-T) + lam ln J H^-T, H^-T = [[h22, -h21], [-h12, h11]] / J
        t11, t12, t21, t22 = h22 / jj, -h21 / jj, -h12 / jj, h11 / jj
        p11 = mu * (h11 - t11) + lam * lj * t11
        p12 = mu * (h12 - t12) + lam * lj * t12
        p21 = mu * (h21 - t21) + lam * lj * t21
        p22 = mu * (h22 - t22) + lam * lj * t22
        # The gradient: A = P F_c^-T on grad_X N_I(g), C = H^T A on b0_I
        a11 = p11 * i11 + p12 * i12
        a12 = p11 * i21 + p12 * i22
        a21 = p21 * i11 + p22 * i12
        a22 = p21 * i21 + p22 * i22
        c11 = h11 * a11 + h21 * a21
        c12 = h11 * a12 + h21 * a22
        c21 = h12 * a11 + h22 * a21
        c22 = h12 * a12 + h22 * a22
        for i in range(4):
            out[2 * i] += w * (a11 * gx[i] + a12 * gy[i] - (c11 * b0x[i] + c12 * b0y[i]))
            out[2 * i + 1] += w * (a21 * gx[i] + a22 * gy[i] - (c21 * b0x[i] + c22 * b0y[i]))
    return e, s2, True
