"""Sandler-Rubin cap model: surfaces, hardening law and invariants (helpers of cap.py).

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
"""

import math

from numba import njit

from pdfem.kernels.params import CAP_A, CAP_B, CAP_C, CAP_D, CAP_KAPPA0, CAP_R, CAP_T, CAP_W


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
def invariants(sig, dev):
    """Return (I1, J = sqrt(J2)) of sig (4,); dev (4,) receives the deviator."""
    i1 = sig[0] + sig[1] + sig[3]
    m = i1 / 3.0
    dev[0] = sig[0] - m
    dev[1] = sig[1] - m
    dev[2] = sig[2]
    dev[3] = sig[3] - m
    j2 = 0.5 * (dev[0] * dev[0] + dev[1] * dev[1] + dev[3] * dev[3]) + dev[2] * dev[2]
    return i1, math.sqrt(j2)


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
    # Tension cut-off
    return max(v, (i1 - tension_limit(p)) / (3.0 * a))
