"""Contact constitutive law (report sec. 5, fig. 6), per unit thickness (plane strain).

Normal: no tension; in compression a hardening law on the mean normal overlap
delta = overlap area / L (L a length fixed for the contact, see contact.py):

    t_n(delta) = kn0 delta / (1 - delta/delta_max)        (traction magnitude, Pa)

stiffness kn0 at delta = 0, tending to infinity at delta_max. So that an explicit run cannot
meet the pole, the law continues beyond delta_c = rcap*delta_max (0 < rcap < 1) as the straight
line tangent to it at delta_c (C1, stiffness frozen at kn0/(1 - rcap)^2); rcap close to 1
(e.g. 0.95) keeps the hyperbola over the whole useful range. The stored energy density is
phi(delta) = kn0 delta_max^2 (-ln(1 - r) - r), r = delta/delta_max, on the hyperbola.

Shear: elastic-perfectly plastic and incremental. u_s (the per-contact history) is the elastic
tangential relative displacement; F_s = ks L u_s with |F_s| <= mu |F_n|; on slip u_s returns to the
limit and the slip times |F_s| is dissipated.

Normal damping (an addition to the report's law, off unless contact.damping > 0): a dashpot
in parallel with the normal spring, acting on the rate of the overlap area (damped_traction;
zeta = 1: critical damping of the contact spring between the masses of the two sides). It
stops the light boundary nodes of a grain bouncing off a hammer at twice its speed, which
folds the grain's outer elements at km/s impacts. Its work is the energy term contact_damping.

Sign: tension positive, so the normal force returned here is F_n = -w t_n <= 0 (normal_force
with w = 1 gives the traction, its tangent and the energy density).
"""

import numpy as np
from numba import njit

# Columns of the per-contact parameter table params[p, :] (float64, SI)
P_KN0 = 0  # initial normal stiffness kn0 [Pa/m] (traction per unit overlap)
P_DMAX = 1  # overlap delta_max at which the normal stiffness would become infinite [m]
P_KS = 2  # shear stiffness ks [Pa/m]
P_MU = 3  # friction coefficient mu [-]
P_RCAP = 4  # delta/delta_max beyond which the law continues linearly, 0 <= rcap < 1 [-]
P_ZETA = 5  # normal damping, fraction of the contact spring's critical damping [-]
P_LAW = 6  # overlap measure: LAW_AREA (the report's) or LAW_POTENTIAL (contact_potential)
NPAR = 7

# Values of params[p, P_LAW]
LAW_AREA = 0.0
LAW_POTENTIAL = 1.0

# Contact time step factor: the contact spring shares its nodes with element stiffness and
# hardens within a step, so take half of the two-mass spring limit 2 sqrt(m_eff/k)
DT_FACTOR = 0.5

# Below this r the energy uses the series -ln(1 - r) - r = sum_{k>=2} r^k/k (no cancellation)
_R_SERIES = 0.05


@njit(cache=True)
def _phi_hyper(r):
    """-ln(1 - r) - r for 0 <= r < 1, accurate for small r."""
    if r < _R_SERIES:
        # Horner form of r^2 (1/2 + r/3 + r^2/4 + ... + r^14/16), truncation < 1e-18 r^2
        s = 0.0
        for k in range(16, 1, -1):
            s = s * r + 1.0 / k
        return s * r * r
    return -np.log1p(-r) - r


@njit(cache=True)
def normal_force(delta, w, kn0, delta_max, rcap):
    """Normal force of a contact of width w [m] and mean overlap delta [m].

    Returns (F, k, E): F = -w t_n(delta) <= 0 [N/m] (tension positive: compression), the tangent
    stiffness k = w dt_n/d(delta) >= 0 [N/m^2] and the stored energy E = w int_0^delta t_n [J/m].
    delta < 0 (a gap) gives (0, 0, 0): the contact carries no tension.
    """
    if delta < 0.0:
        return 0.0, 0.0, 0.0
    rc = rcap
    dc = rc * delta_max
    if delta <= dc:
        # On the hyperbola
        r = delta / delta_max
        g = 1.0 - r
        t = kn0 * delta / g
        k = kn0 / (g * g)
        e = kn0 * delta_max * delta_max * _phi_hyper(r)
    else:
        # Tangent line beyond the cap
        g = 1.0 - rc
        tc = kn0 * dc / g
        k = kn0 / (g * g)
        e0 = kn0 * delta_max * delta_max * _phi_hyper(rc)
        dd = delta - dc
        t = tc + k * dd
        e = e0 + tc * dd + 0.5 * k * dd * dd
    return -w * t, w * k, w * e


@njit(cache=True)
def shear_update(us, dus, w, ks, mu, fn):
    """Incremental elastic-perfectly plastic shear.

    us: elastic tangential relative displacement at the start of the step [m]; dus: its increment;
    w: the contact's length [m] (contact.py: L); fn: the normal force (its magnitude sets the
    limit mu |fn|). Returns (us_new, Fs, diss): the updated history, the shear force
    Fs = ks w us_new [N/m] and the frictional dissipation of the step mu |fn| |slip| [J/m].
    """
    kw = ks * w
    trial = us + dus
    fs = kw * trial
    lim = mu * abs(fn)
    if abs(fs) <= lim:
        return trial, fs, 0.0
    # Slip: return to the friction limit, dissipate limit x slip
    if kw > 0.0:
        us_new = np.copysign(lim / kw, trial)
    else:
        us_new = 0.0
    fs = np.copysign(lim, trial)
    return us_new, fs, lim * abs(trial - us_new)


@njit(cache=True)
def effective_mass(m1, m2):
    """m1 m2 / (m1 + m2), or m1 when m2 <= 0 or infinite (a rigid wall)."""
    if m2 <= 0.0 or not np.isfinite(m2):
        return m1
    return m1 * m2 / (m1 + m2)


@njit(cache=True)
def damped_traction(tn, kt, rate, meff, length, gn, zeta):
    """Normal traction with the dashpot on the overlap area (module docstring).

    tn: the law's traction [Pa]; kt its tangent [Pa/m]; rate: dA/dt of the overlap area
    [m^2/s]; meff: effective mass of the sides [kg/m]; length: the pair's L [m]; gn: |dA/dx| of
    side A [m]. Returns max(tn + c_A rate, 0) with c_A = 2 zeta sqrt(meff kt / L) / gn, which is
    zeta times the critical damping of the normal spring k_t gn^2 / L; tn when zeta or gn is 0.
    """
    if zeta <= 0.0 or gn <= 0.0:
        return tn
    return max(tn + 2.0 * zeta * np.sqrt(meff * kt / length) / gn * rate, 0.0)


@njit(cache=True)
def contact_dt(m1, m2, k, zeta=0.0):
    """Stable step DT_FACTOR * 2 sqrt(m_eff/k) of a contact spring between masses m1 and m2,
    times sqrt(1 + zeta^2) - zeta for a dashpot of damping ratio zeta.

    k is the *current* tangent stiffness (it grows without bound as delta -> delta_max); m2 <= 0
    or infinite means a rigid wall (m_eff = m1). Returns inf when k <= 0.
    """
    if k <= 0.0:
        return np.inf
    meff = effective_mass(m1, m2)
    return DT_FACTOR * 2.0 * np.sqrt(meff / k) * (np.sqrt(1.0 + zeta * zeta) - zeta)
