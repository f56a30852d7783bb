"""Sandler-Rubin cap plasticity (report section 6, eqs. 76-79): material point update.

Sign convention: tension positive, compression negative. I1 = tr(sigma) with sigma_zz
included (plane strain carries sigma_zz); J2 from the deviator of the full 3-D stress
(xx, yy, zz, xy). Stress and strain-increment vectors are ordered (xx, yy, xy, zz) and the xy
strain entry is the tensor component. Surfaces and hardening law: see cap_surface.py.

Return algorithm (backward Euler, associated flow on every surface, in invariant space since
the deviator keeps the direction of the trial deviator s_t):
    cap (trial I1 < L):       nested scalar solves; outer Newton/bisection on kappa so that
                              H(kappa) - H(kappa_n) = eps_v^p increment (consistent hardening),
                              inner closest point on the ellipse of that kappa
    envelope (I1 >= L):       scalar Newton on I1 (perfectly plastic; F concave, so the
                              elastic domain J <= F(I1) is convex)
    envelope/cap corner:      when the envelope return would land at I1 < L(kappa): stress at
                              I1 = L, J = F(L), both multipliers >= 0
    tension cut-off I1 <= T:  I1 = T with s unchanged, or the T/envelope corner (I1 = T,
                              J = F(T)) when J would exceed the envelope there
Every mode has eps_v^p increment = (I1_trial - I1)/(3K).

Dilatancy (flow on the envelope or the cut-off) retracts the cap through the same hardening
law, but kappa never rises above max(kappa_n, 0) (Sandler-Rubin: L = min(kappa, 0), the cap
stops retracting when L reaches the origin, as the McCormick table shows from eps = +0.012)
nor past the current stress I1 (so an envelope point stays on the envelope side of the
corner; without this limit the softening cap can overtake the stress and the backward-Euler
system has no solution). Dilatancy beyond those limits is kept in eps_v^p (st[1]) but not in
kappa; later compaction hardens kappa incrementally from where it stands.

kappa > 0 (only an initial state: kappa0 > 0 puts X0 near 0): the 1979 geometry then has a
step at I1 = 0 between the cap top -X/R and the envelope F(0), i.e. a non-convex elastic
domain. The trial I1 picks the side (cap_side); the corner there is (0, F(0)).

Accuracy: the increment is split into 1 + int(overshoot/SUB_ETA) equal substeps (overshoot =
normalised yield value of the trial, in units of A, taken against the larger of A and the
trial's mean stress |I1|/3: cap_substeps; at most NSUB_MAX), so results hardly depend on the
increment size: one increment vs ten differ by < 0.5 % of max(A, |sigma|) in the tests
(kappa <= 0), by up to 4 % for paths crossing the kappa > 0 step.

Rate dependence (p[CAP_TAU] = tau > 0): the Duvaut-Lions overstress form of the cap (Simo, Ju,
Pister & Taylor, J. Eng. Mech. 114, 191, 1988). The rate-independent update above gives, from
the same start, the stress sigma_bar and the state q_bar of the step; the viscoplastic point
relaxes towards them over tau, backward Euler over the step dt:
    sigma = (sigma_trial + (dt/tau) sigma_bar) / (1 + dt/tau),  q = q_n + r (q_bar - q_n),
    r = dt / (tau + dt),
for every state entry (kappa and the plastic strains, so that sigma = C:(eps - eps^p) still
holds). The stress may stay outside the surface (the overstress); tau -> 0 gives r -> 1, the
rate-independent update, and tau = 0 takes that update itself. A step of zero duration
(dt = 0) is elastic. The plastic strain of the step is deps^p = C^-1:(sigma_trial - sigma) =
r deps^p_bar, and its work r w_bar + (sigma - sigma_bar):deps^p = r (w_bar + (1 - r) (sigma_trial -
sigma_bar):C^-1:(sigma_trial - sigma_bar)) >= 0, with w_bar the rate-independent update's own
(substepped) plastic work: the end stress's sigma:deps^p with the rate-independent part taken
along its path, so that it tends to the rate-independent work as tau -> 0.

State row st (CAP_NST = 6): kappa, eps_v^p, eps^p (xx, yy, xy, zz).
Status: 0 ok, 1 a local solve did not converge, 2 stress left outside the surface by more
than tol (p[CAP_TOL], 1e-8 when 0) after the update, 3 non-finite input or result.
"""

import math

from numba import njit

from pdfem.kernels.cap_surface import (
    cap_l,
    cap_return,
    cap_rho,
    cap_side,
    cap_x,
    corner_kappa,
    dilate_kappa,
    env_f,
    env_slope,
    envelope_i1,
    tension_limit,
    x0,
    yield_value,
)
from pdfem.kernels.params import (
    BULK,
    CAP_A,
    CAP_B,
    CAP_C,
    CAP_D,
    CAP_KAPPA0,
    CAP_R,
    CAP_T,
    CAP_TAU,
    CAP_TOL,
    CAP_W,
    SHEAR,
)

CAP_NST = 6  # kappa, eps_v^p, eps^p xx, yy, xy, zz
CAP_OK = 0
CAP_NO_CONVERGENCE = 1
CAP_OUTSIDE = 2
CAP_NONFINITE = 3

TOL_DEFAULT = 1e-8  # yield tolerance when p[CAP_TOL] is 0
SUB_ETA = 0.01  # target normalised trial overshoot per substep
NSUB_MAX = 2000  # substep cap


@njit(cache=True)
def cap_initial_state(p, st):
    """Initial state row: kappa = p[CAP_KAPPA0], no plastic strain."""
    st[0] = p[CAP_KAPPA0]
    for i in range(1, CAP_NST):
        st[i] = 0.0


@njit(cache=True)
def cap_tolerance(p):
    """Normalised yield tolerance: p[CAP_TOL], or 1e-8 when it is 0."""
    return p[CAP_TOL] if p[CAP_TOL] > 0.0 else TOL_DEFAULT


@njit(cache=True)
def cap_yield_value(p, sig, st):
    """Largest active normalised yield function at stress sig (4,) and state st (> 0: out)."""
    i1 = sig[0] + sig[1] + sig[3]
    m = i1 / 3.0
    sx = sig[0] - m
    sy = sig[1] - m
    sz = sig[3] - m
    j = math.sqrt(0.5 * (sx * sx + sy * sy + sz * sz) + sig[2] * sig[2])
    return yield_value(p, i1, j, st[0])


@njit(cache=True)
def _trial(p, sig, d0, d1, d2, d3):
    """Elastic trial stress sig + C:d as four scalars (same arithmetic as elastic_update)."""
    g2 = 2.0 * p[SHEAR]
    lam = p[BULK] - g2 / 3.0
    dv = d0 + d1 + d3
    return (sig[0] + (lam * dv + g2 * d0), sig[1] + (lam * dv + g2 * d1),
            sig[2] + g2 * d2, sig[3] + (lam * dv + g2 * d3))


@njit(cache=True)
def _return_invariants(p, i1t, jt, kap, xa, tn):
    """Plastic return in invariant space: (I1, J, kappa, converged, plastic)."""
    kb = p[BULK]
    gs = p[SHEAR]
    el = cap_l(kap)
    # Cap side of the corner
    if cap_side(p, i1t, kap):
        r = p[CAP_R]
        if math.sqrt(r * r * jt * jt + (i1t - el) ** 2) <= cap_rho(p, kap):
            return i1t, jt, kap, True, False
        i1, j, kn, ok = cap_return(p, i1t, jt, kap, xa, kb, gs)
        return i1, j, kn, ok, True
    # Envelope side: elastic, tension cut-off, tension corner or envelope
    if i1t <= tn and jt <= env_f(p, i1t):
        return i1t, jt, kap, True, False
    envelope = True
    i1 = i1t
    j = jt
    if i1t > tn:
        ftn = env_f(p, tn)
        if jt <= ftn:
            i1 = tn
            envelope = False
        elif i1t - tn - 9.0 * kb * (jt - ftn) / gs * env_slope(p, tn) >= 0.0:
            i1 = tn
            j = ftn
            envelope = False
    ok = True
    if envelope:
        i1, ok = envelope_i1(p, i1t, jt, kb, gs)
        j = max(env_f(p, i1), 0.0)
        # Past the corner: stress at I1 = L(kappa), J = F(L)
        if i1 < el:
            kn, ok = corner_kappa(p, i1t, kap, xa, kb)
            i1 = cap_l(kn)
            return i1, env_f(p, i1), kn, ok, True
    # Dilatancy retracts the cap, never past the origin or the stress
    kn = dilate_kappa(p, kap, (i1t - i1) / (3.0 * kb), max(kap, min(0.0, i1)), xa)
    return i1, j, kn, ok, True


@njit(cache=True)
def _step(p, sig, st, d0, d1, d2, d3, xa, tn):
    """One backward-Euler increment; updates sig, st in place; returns (converged, dwp)."""
    kb = p[BULK]
    g2 = 2.0 * p[SHEAR]
    t0, t1, t2, t3 = _trial(p, sig, d0, d1, d2, d3)
    i1t = t0 + t1 + t3
    m = i1t / 3.0
    s0 = t0 - m
    s1 = t1 - m
    s2 = t2
    s3 = t3 - m
    jt = math.sqrt(0.5 * (s0 * s0 + s1 * s1 + s3 * s3) + s2 * s2)
    i1, j, kn, ok, plastic = _return_invariants(p, i1t, jt, st[0], xa, tn)
    # Elastic: the trial stands
    if not plastic:
        sig[0] = t0
        sig[1] = t1
        sig[2] = t2
        sig[3] = t3
        return ok, 0.0
    # Deviator scaled along the trial direction, new mean stress
    f = j / jt if jt > 0.0 else 0.0
    m = i1 / 3.0
    sig[0] = f * s0 + m
    sig[1] = f * s1 + m
    sig[2] = f * s2
    sig[3] = f * s3 + m
    # Plastic strain increment C^-1:(trial - sigma) and its work sigma:deps^p
    dv = (i1t - i1) / (3.0 * kb)
    e0 = (1.0 - f) * s0 / g2
    e1 = (1.0 - f) * s1 / g2
    e2 = (1.0 - f) * s2 / g2
    e3 = (1.0 - f) * s3 / g2
    dwp = f * (s0 * e0 + s1 * e1 + s3 * e3 + 2.0 * s2 * e2) + m * dv
    st[0] = kn
    st[1] += dv
    st[2] += e0 + dv / 3.0
    st[3] += e1 + dv / 3.0
    st[4] += e2
    st[5] += e3 + dv / 3.0
    return ok, dwp


@njit(cache=True)
def cap_substeps(p, sig, d0, d1, d3, over):
    """Substeps of a plastic increment from stress sig (4,) with normalised overshoot over (the
    trial's yield value, a multiple of A): 1 + int(rel / SUB_ETA), at most NSUB_MAX, with rel the
    overshoot against the larger of A and the trial's mean stress |I1_t| / 3. The accuracy is
    relative to max(A, |sigma|); a cap crushed to tens of GPa moves by many A in one increment,
    and counted in A alone would take the cap's walk in thousands of substeps."""
    a = p[CAP_A]
    i1t = sig[0] + sig[1] + sig[3] + 3.0 * p[BULK] * (d0 + d1 + d3)
    rel = over * (a / max(a, abs(i1t) / 3.0))
    return min(NSUB_MAX, 1 + int(rel / SUB_ETA))


@njit(cache=True)
def _plastic_update(p, sig, st, d0, d1, d2, d3, over):
    """Substepped plastic update of cap_update for a trial with normalised overshoot over."""
    # Substeps: more of them the further the trial lies outside, against the stress's size
    nsub = cap_substeps(p, sig, d0, d1, d3, over)
    xa = x0(p)
    tn = tension_limit(p)
    w = 1.0 / nsub
    dwp = 0.0
    status = CAP_OK
    for _ in range(nsub):
        ok, dw = _step(p, sig, st, w * d0, w * d1, w * d2, w * d3, xa, tn)
        dwp += dw
        if not ok:
            status = CAP_NO_CONVERGENCE
    # Guards: finite, on or inside the surface
    if not math.isfinite(sig[0] + sig[1] + sig[2] + sig[3] + st[0] + dwp):
        return CAP_NONFINITE, dwp
    if status == CAP_OK and cap_yield_value(p, sig, st) > cap_tolerance(p):
        status = CAP_OUTSIDE
    return status, dwp


@njit(cache=True)
def _relaxed_update(p, sig, st, d0, d1, d2, d3, over, dt):
    """Duvaut-Lions update (module docstring) of a trial with normalised overshoot over: the
    rate-independent update from the same start, and the point relaxed towards it by
    r = dt / (tau + dt)."""
    t0, t1, t2, t3 = _trial(p, sig, d0, d1, d2, d3)
    # The rate-independent stress and state of the step, from copies of the start
    sb = sig.copy()
    qb = st.copy()
    status, dwb = _plastic_update(p, sb, qb, d0, d1, d2, d3, over)
    r = dt / (p[CAP_TAU] + dt)
    # Stress between the trial and the rate-independent stress; state likewise from q_n
    sig[0] = t0 + r * (sb[0] - t0)
    sig[1] = t1 + r * (sb[1] - t1)
    sig[2] = t2 + r * (sb[2] - t2)
    sig[3] = t3 + r * (sb[3] - t3)
    for k in range(CAP_NST):
        st[k] += r * (qb[k] - st[k])
    # Plastic strain of the step, C^-1:(trial - sigma) = r times the rate-independent one,
    # and its work: r times the rate-independent work plus the overstress's share
    kb = p[BULK]
    g2 = 2.0 * p[SHEAR]
    i1 = sig[0] + sig[1] + sig[3]
    m = i1 / 3.0
    mt = (t0 + t1 + t3) / 3.0
    dv = (t0 + t1 + t3 - i1) / (3.0 * kb)
    e0 = ((t0 - mt) - (sig[0] - m)) / g2
    e1 = ((t1 - mt) - (sig[1] - m)) / g2
    e2 = (t2 - sig[2]) / g2
    e3 = ((t3 - mt) - (sig[3] - m)) / g2
    v3 = dv / 3.0
    dwp = r * dwb + ((sig[0] - sb[0]) * (e0 + v3) + (sig[1] - sb[1]) * (e1 + v3)
                     + (sig[3] - sb[3]) * (e3 + v3) + 2.0 * (sig[2] - sb[2]) * e2)
    if not math.isfinite(sig[0] + sig[1] + sig[2] + sig[3] + st[0] + dwp):
        return CAP_NONFINITE, dwp
    return status, dwp


@njit(cache=True)
def plastic_update(p, sig, st, d0, d1, d2, d3, over, dt):
    """The update of a point whose elastic trial lies outside (normalised overshoot over > 0)
    over a step of duration dt: rate-independent (p[CAP_TAU] = 0) or relaxed (> 0).
    Returns (status, dwp)."""
    if p[CAP_TAU] > 0.0:
        return _relaxed_update(p, sig, st, d0, d1, d2, d3, over, dt)
    return _plastic_update(p, sig, st, d0, d1, d2, d3, over)


@njit(cache=True)
def cap_update(p, sig, deps, st, dt=0.0):
    """Cap model update of stress sig (4,) in place for strain increment deps (4,).

    p: parameter row (params.py columns BULK, SHEAR, CAP_A .. CAP_TAU); st: state row of
    length CAP_NST (see cap_initial_state); dt: the step's duration, used only by a
    rate-dependent point (p[CAP_TAU] > 0; a step of zero duration is elastic there).
    Returns (status, dwp) with dwp = sigma:deps^p >= 0 the plastic work density increment.
    On a nonzero status the state is left as computed.
    """
    d0, d1, d2, d3 = deps[0], deps[1], deps[2], deps[3]
    if not (math.isfinite(d0 + d1 + d2 + d3) and math.isfinite(sig[0] + sig[1] + sig[2]
                                                                + sig[3] + st[0])):
        return CAP_NONFINITE, 0.0
    # Elastic trial: done when it is inside
    t0, t1, t2, t3 = _trial(p, sig, d0, d1, d2, d3)
    i1t = t0 + t1 + t3
    m = i1t / 3.0
    jt = math.sqrt(0.5 * ((t0 - m) ** 2 + (t1 - m) ** 2 + (t3 - m) ** 2) + t2 * t2)
    over = yield_value(p, i1t, jt, st[0])
    if over <= 0.0:
        sig[0] = t0
        sig[1] = t1
        sig[2] = t2
        sig[3] = t3
        return CAP_OK, 0.0
    return plastic_update(p, sig, st, d0, d1, d2, d3, over, dt)


def cap_check_params(p):
    """Return '' when the cap parameters of row p are usable, else a short reason."""
    kb, gs = p[BULK], p[SHEAR]
    a, b, c, d, r, w = p[CAP_A], p[CAP_B], p[CAP_C], p[CAP_D], p[CAP_R], p[CAP_W]
    vals = (kb, gs, a, b, c, d, r, w, p[CAP_KAPPA0], p[CAP_T], p[CAP_TOL], p[CAP_TAU])
    # Finite values and positive moduli
    if not all(math.isfinite(v) for v in vals):
        return "cap parameters must be finite"
    if kb <= 0.0 or gs <= 0.0:
        return "bulk and shear moduli must be > 0"
    # Envelope, cap and hardening constants
    if not a > c >= 0.0:
        return "need A > C >= 0"
    if b < 0.0:
        return "need B >= 0"
    if d <= 0.0:
        return "need D > 0"
    if r <= 0.0:
        return "need R > 0"
    if not 0.0 < w < 1.0:
        return "need 0 < W < 1"
    # Tension cut-off between the origin and the envelope apex
    t = p[CAP_T]
    if t < 0.0:
        return "need tension cut-off T >= 0"
    if c > 0.0 and b > 0.0 and t > math.log(a / c) / b * (1.0 + 1e-12):
        return f"tension cut-off T = {t:g} is beyond the envelope apex {math.log(a / c) / b:g}"
    # Initial cap must cross the I1 axis on the compressive side
    if cap_x(p, p[CAP_KAPPA0]) > 1e-12 * r * a:
        return "initial cap X(kappa0) = kappa0 - R F(kappa0) must be <= 0"
    if not 0.0 <= p[CAP_TOL] < 1e-2:
        return "tol must be in [0, 1e-2)"
    if p[CAP_TAU] < 0.0:
        return "need relaxation_time >= 0"
    return ""

