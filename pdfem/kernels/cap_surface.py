"""Sandler-Rubin cap model: surfaces, hardening law and the scalar return solves (for cap.py).

Sign convention: tension positive, compression negative. I1 = tr(sigma) with sigma_zz
included; J = sqrt(J2) with J2 = s:s/2 of the full 3-D deviator (xx, yy, zz, xy; xy counted
twice). Stress vectors are ordered (xx, yy, xy, zz).

Surfaces (compression negative, everything in I1 units or J units):
    F(I1)  = A - C exp(B I1)                      failure envelope (J units)
    f1     = J - F(I1)                            envelope, active for I1 >= L
    L(k)   = min(k, 0)                            cap/envelope intersection (Sandler-Rubin)
    X(k)   = k - R F(k)                           where the cap meets the I1 axis
    rho(k) = L(k) - X(k)                          cap semi-axis along I1 (= R F(k) for k <= 0)
    f2     = sqrt(R^2 J^2 + (I1 - L)^2) - rho     cap, active for I1 < L
    f3     = I1 - T                               tension cut-off (T <= envelope apex)
For k <= 0 the cap is the ellipse ((L - I1)/(R F(L)))^2 + J2/F(L)^2 = 1 of NeoPZ/Albany.
For k > 0 (only an initial state can have it: dilatancy never raises k above max(k, 0)) the
ellipse is centred at L = 0 with semi-axes -X and -X/R; this is the 1979 rule that the
McCormick Ranch table needs at its second row.

Hardening (relative to the initial cap X0 = X(kappa0), Albany form):
    eps_v^p = W (exp(D (X - X0)) - 1) = H(k) - W,   H(k) = W exp(D (X(k) - X0)).

The solves below work in invariant space (I1, J) with bulk modulus kb = K and shear modulus
gs = G; each is a safeguarded Newton iteration inside a bracket that holds the root.
"""

import math

from numba import njit

from pdfem.kernels.params import CAP_A, CAP_B, CAP_C, CAP_D, CAP_KAPPA0, CAP_R, CAP_T, CAP_W

MAXIT = 200  # iterations of every local scalar solve


@njit(cache=True)
def env_f(p, i1):
    """Failure envelope F(I1) = A - C exp(B I1) [J units]."""
    return p[CAP_A] - p[CAP_C] * math.exp(p[CAP_B] * i1)


@njit(cache=True)
def env_slope(p, i1):
    """-dF/dI1 = C B exp(B I1) >= 0 (the I1 component of the envelope normal)."""
    return p[CAP_C] * p[CAP_B] * math.exp(p[CAP_B] * i1)


@njit(cache=True)
def apex(p):
    """I1 where the envelope reaches J = 0: ln(A/C)/B, or +inf without an apex."""
    if p[CAP_C] > 0.0 and p[CAP_B] > 0.0:
        return math.log(p[CAP_A] / p[CAP_C]) / p[CAP_B]
    return math.inf


@njit(cache=True)
def tension_limit(p):
    """Effective tension cut-off on I1: min(T, apex)."""
    return min(p[CAP_T], apex(p))


@njit(cache=True)
def cap_l(kap):
    """Cap/envelope intersection L = min(kappa, 0)."""
    return min(kap, 0.0)


@njit(cache=True)
def cap_side(p, i1, kap):
    """True when I1 is on the cap side of the corner: I1 < L beyond round-off.

    A point within 1e-12 (|L| + R A) of L counts as the envelope side. This matters only for
    kappa > 0, where the surface has a step at I1 = 0 and the envelope/cap corner (0, F(0)),
    recomposed from components, must not fall onto the much smaller cap by round-off.
    """
    el = cap_l(kap)
    return i1 < el - 1e-12 * (abs(el) + p[CAP_R] * p[CAP_A])


@njit(cache=True)
def cap_x(p, kap):
    """Cap intersection with the I1 axis, X = kappa - R F(kappa)."""
    return kap - p[CAP_R] * env_f(p, kap)


@njit(cache=True)
def cap_rho(p, kap):
    """Semi-axis of the cap along I1, L - X (clamped at 0)."""
    return max(cap_l(kap) - cap_x(p, kap), 0.0)


@njit(cache=True)
def x0(p):
    """Initial cap position X0 = X(kappa0)."""
    return cap_x(p, p[CAP_KAPPA0])


@njit(cache=True)
def hard_h(p, kap, xa):
    """H(kappa) = W exp(D (X(kappa) - X0)); eps_v^p = H - W. xa is X0."""
    return p[CAP_W] * math.exp(p[CAP_D] * (cap_x(p, kap) - xa))


@njit(cache=True)
def hard_dh(p, kap, xa):
    """dH/dkappa = D H (1 + R C B exp(B kappa)) > 0."""
    return p[CAP_D] * hard_h(p, kap, xa) * (1.0 + p[CAP_R] * env_slope(p, kap))


@njit(cache=True)
def yield_value(p, i1, j, kap):
    """Normalised yield value at (I1, J) for cap position kappa: > 0 means outside.

    Envelope and tension values are divided by A and 3A, the cap by R A, so that all read as
    fractions of the shear strength scale A.
    """
    a = p[CAP_A]
    # Cap for I1 < L, envelope otherwise
    if cap_side(p, i1, kap):
        el = cap_l(kap)
        r = p[CAP_R]
        v = (math.sqrt(r * r * j * j + (i1 - el) ** 2) - cap_rho(p, kap)) / (r * a)
    else:
        v = (j - env_f(p, i1)) / a
    # Tension cut-off (T <= apex is checked by cap_check_params; returns use min(T, apex))
    return max(v, (i1 - p[CAP_T]) / (3.0 * a))


@njit(cache=True)
def envelope_i1(p, i1t, jt, kb, gs):
    """I1 of the backward-Euler return onto the envelope; returns (I1, converged).

    Root of r(I1) = I1 - I1t + (9K/G) (-F'(I1)) (Jt - F(I1)), increasing and convex on the
    bracket [max(I1t - r(I1t), F^-1(Jt)), I1t], so Newton from the right converges.
    """
    q = 9.0 * kb / gs
    sl = env_slope(p, i1t)
    over = q * sl * (jt - env_f(p, i1t))
    if over <= 0.0:
        return i1t, True
    # Bracket
    hi = i1t
    lo = i1t - over
    a, b, c = p[CAP_A], p[CAP_B], p[CAP_C]
    if jt < a and c > 0.0 and b > 0.0:
        lo = max(lo, math.log((a - jt) / c) / b)
    # Safeguarded Newton from the right end
    x = hi
    rtol = 1e-14 * (abs(i1t) + 3.0 * a)
    for _ in range(MAXIT):
        sl = env_slope(p, x)
        fj = jt - env_f(p, x)
        r = x - i1t + q * sl * fj
        if abs(r) <= rtol:
            return x, True
        if r > 0.0:
            hi = x
        else:
            lo = x
        xn = x - r / (1.0 + q * (b * sl * fj + sl * sl))
        if not (lo <= xn <= hi):
            xn = 0.5 * (lo + hi)
        if abs(xn - x) <= 1e-15 * (abs(x) + a):
            return xn, True
        x = xn
    return x, False


@njit(cache=True)
def dilate_kappa(p, kap, depv, lim, xa):
    """Kappa after a dilatant eps_v^p increment depv >= 0, at most lim (>= kap)."""
    if depv <= 0.0 or lim <= kap:
        return kap
    ht = hard_h(p, kap, xa) + depv
    if hard_h(p, lim, xa) <= ht:
        return lim
    # H is increasing: safeguarded Newton on [kap, lim]
    lo = kap
    hi = lim
    k = kap
    for _ in range(MAXIT):
        r = hard_h(p, k, xa) - ht
        if r > 0.0:
            hi = k
        else:
            lo = k
        # A slope that underflows (H far down its exponential) bisects instead
        dh = hard_dh(p, k, xa)
        kn = k - r / dh if dh > 0.0 else 0.5 * (lo + hi)
        if not (lo <= kn <= hi):
            kn = 0.5 * (lo + hi)
        if abs(kn - k) <= 1e-15 * (abs(k) + p[CAP_R] * p[CAP_A]):
            return kn
        k = kn
    return k


@njit(cache=True)
def corner_kappa(p, i1t, kap, xa, kb):
    """Kappa at the envelope/cap corner: H(k) - H(kap) = (I1t - L(k))/(3K), k <= max(kap, 0)."""
    if kap >= 0.0:
        return kap, True
    h0 = hard_h(p, kap, xa)
    if hard_h(p, 0.0, xa) - h0 - i1t / (3.0 * kb) <= 0.0:
        return 0.0, True
    # phi is increasing on [kap, 0]: safeguarded Newton
    lo = kap
    hi = 0.0
    k = kap
    for _ in range(MAXIT):
        r = hard_h(p, k, xa) - h0 - (i1t - k) / (3.0 * kb)
        if r > 0.0:
            hi = k
        else:
            lo = k
        dh = hard_dh(p, k, xa) + 1.0 / (3.0 * kb)
        kn = k - r / dh if dh > 0.0 else 0.5 * (lo + hi)
        if not (lo <= kn <= hi):
            kn = 0.5 * (lo + hi)
        if abs(kn - k) <= 1e-15 * (abs(k) + p[CAP_R] * p[CAP_A]):
            return kn, True
        k = kn
    return k, False


@njit(cache=True)
def cap_point(p, i1t, jt, kap, kb, gs):
    """Backward-Euler return onto the cap of fixed position kap; returns (I1, J, dI1/dkappa).

    With s = 1/(1 + 9K dlam/rho): I1 - L = (I1t - L) s, J = Jt s/(c + (1 - c) s), c = G R^2/9K,
    and s solves s sqrt((R Jt/(c + (1 - c) s))^2 + (I1t - L)^2) = rho (increasing in s).
    """
    r = p[CAP_R]
    el = cap_l(kap)
    dl = 1.0 if kap < 0.0 else 0.0
    rho = cap_rho(p, kap)
    a = i1t - el
    c = gs * r * r / (9.0 * kb)
    rj = r * jt
    # Inside (s = 1), degenerate cap (s = 0), or safeguarded Newton on [0, 1]
    mm = math.sqrt(rj * rj + a * a)
    if mm <= rho:
        return i1t, jt, 0.0
    s = 0.0
    if rho > 0.0:
        s = rho / mm
        lo = 0.0
        hi = 1.0
        gtol = 1e-15 * (mm + rho)
        for _ in range(MAXIT):
            w = c + (1.0 - c) * s
            mm = math.sqrt((rj / w) ** 2 + a * a)
            g = s * mm - rho
            if abs(g) <= gtol:
                break
            if g > 0.0:
                hi = s
            else:
                lo = s
            dm = -(rj * rj) * (1.0 - c) / (mm * w * w * w)
            sn = s - g / (mm + s * dm)
            if not (lo < sn < hi):
                sn = 0.5 * (lo + hi)
            if hi - lo <= 1e-16:
                s = sn
                break
            s = sn
    w = c + (1.0 - c) * s
    mm = math.sqrt((rj / w) ** 2 + a * a)
    dm = -(rj * rj) * (1.0 - c) / (mm * w * w * w)
    # Sensitivity of the return point to the cap position
    drho = dl - 1.0 - r * env_slope(p, kap)
    if rho <= 0.0:
        drho = max(drho, 0.0)
    dgdk = -s * a * dl / mm - drho
    dsdk = -dgdk / (mm + s * dm)
    return el + a * s, jt * s / w, dl * (1.0 - s) + a * dsdk


@njit(cache=True)
def cap_return(p, i1t, jt, kap, xa, kb, gs):
    """Cap return with consistent hardening; returns (I1, J, kappa, converged).

    Root in (I1t, kap) of h(k) = H(k) - H(kap) + (I1(k) - I1t)/(3K): h(kap) > 0 and
    h -> H(I1t) - H(kap) < 0 as k -> I1t (the cap then passes just above the trial I1).
    """
    h0 = hard_h(p, kap, xa)
    lo = i1t
    hi = kap
    k = kap
    htol = max(1e-13 * (cap_l(kap) - i1t) / (3.0 * kb), 4e-16 * (h0 + p[CAP_W]))
    ktol = 1e-15 * (abs(kap) + abs(i1t) + p[CAP_R] * p[CAP_A])
    for _ in range(MAXIT):
        i1, j, di1 = cap_point(p, i1t, jt, k, kb, gs)
        h = hard_h(p, k, xa) - h0 + (i1 - i1t) / (3.0 * kb)
        if abs(h) <= htol:
            return i1, j, k, True
        if h > 0.0:
            hi = k
        else:
            lo = k
        dh = hard_dh(p, k, xa) + di1 / (3.0 * kb)
        kn = k - h / dh if dh > 0.0 else 0.5 * (lo + hi)
        if not (lo < kn < hi):
            kn = 0.5 * (lo + hi)
        if abs(kn - k) <= ktol:
            i1, j, di1 = cap_point(p, i1t, jt, kn, kb, gs)
            return i1, j, kn, True
        k = kn
    i1, j, di1 = cap_point(p, i1t, jt, k, kb, gs)
    return i1, j, k, False
