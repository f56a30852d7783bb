"""Bulk response on a crystal's linear Us-up Hugoniot (an equation of state of the grains).

A material with ``eos = "us_up"`` keeps the hypo-elastic stress update of its model, but its
bulk modulus follows the pressure-volume curve of the shock Hugoniot Us = c0 + s up
(Mie-Gruneisen with the Hugoniot as reference curve and Gamma = 0):

    p_H(eta) = K0 eta / (1 - s eta)^2,    eta = 1 - V/V0 in [0, 1/s),   K0 = rho0 c0^2
    K(p)     = -V dp_H/dV = (1 - eta) K0 (1 + s eta) / (1 - s eta)^3,   eta = eta(p)

with eta(p) = 2 / (2 s + r + sqrt(r^2 + 4 s r)), r = K0 / p, the root of p (1 - s eta)^2 = K0 eta
below 1/s. A step takes the secant modulus along p_H: the point's pressure p_n gives its
compression eta_n = eta(p_n), the step's volumetric strain dv moves it to
1 - eta_{n+1} = (1 - eta_n) exp(dv), and K = (p_n - p_H(eta_{n+1})) / dv. A purely volumetric
step then ends on p_H exactly, so a point compressed to eta carries p_H(eta) whatever its
steps, a closed load-unload cycle returns to its pressure (its trapezoidal stress work
vanishes to second order in the step), and a steady
shock's jump state lies on the Hugoniot. In tension (p <= 0) p_H is linear in eta. A step
stops at eta = ETA_MAX / s (the pressure there stops the run through the stable step). K0 is
the material's ``bulk`` (after any temperature softening), s its ``eos_s``. Sign convention:
tension positive, p = -tr(sigma)/3 (sigma_zz included, plane strain).

With a Gruneisen coefficient Gamma0 = ``eos_gamma`` > 0 the pressure is Mie-Gruneisen on that
Hugoniot with Gamma rho = Gamma0 rho0:

    p = p_H(eta) + Gamma0 (e - e_H(eta)) = p_r(eta) + Gamma0 e,   e_H = p_H eta / 2,
    p_r(eta) = p_H(eta) (1 - Gamma0 eta / 2),

e the point's internal energy per unit reference volume (the last column of its state row),
from the rest state. The state is (stress, e): p - Gamma0 e = p_r(eta) gives eta in closed
form (reference_eta, the root of a quadratic; p_r rises with eta for Gamma0 < 2 s). A step
moves eta as above and adds to e the pressure's trapezoidal work, the bulk viscosity's work
q (-dv) and the deviatoric stress work, each per reference volume (times J = 1 - eta at
mid-step). The secant modulus takes the step to the Mie-Gruneisen pressure of eta_{n+1} with
the first two (gruneisen_row); the deviatoric work, known only after the material's update,
raises the pressure at constant volume by Gamma0 J w_dev (gruneisen_heat). A purely
volumetric step without viscosity therefore ends on the isentrope of the form, a closed cycle
returns e and p to their start to second order in the step, and a steady shock, whose
dissipation the viscosity carries, ends on the Hugoniot: the reference curve is the Hugoniot,
so its states are the form's.
"""

import math

from numba import njit

from pdfem.kernels.params import BULK, EOS_G, EOS_S, RHO, SHEAR

# A step never compresses a point past this fraction of the limit eta = 1/s: the pressure
# there, about 10^6 K0, stops the run through the stable step
ETA_MAX = 0.999


@njit(cache=True)
def hugoniot_pressure(k0, s, eta):
    """p_H(eta) of the module docstring [Pa] (eta < 1/s; linear K0 eta for eta < 0)."""
    if eta <= 0.0:
        return k0 * eta
    g = 1.0 - s * eta
    return k0 * eta / (g * g)


@njit(cache=True)
def hugoniot_bulk(k0, s, pressure):
    """Tangent bulk modulus K(p) [Pa] of the module docstring at pressure p (compression
    positive); K0 for p <= 0 or s <= 0, +inf where eta(p) rounds to the limit 1/s (or p is
    not finite), which the stable step and the non-finite guard then stop on."""
    if not (s > 0.0 and pressure > 0.0):
        return k0
    eta = hugoniot_eta(k0, s, pressure)
    g = 1.0 - s * eta
    if not g > 0.0:
        return math.inf
    return (1.0 - eta) * k0 * (1.0 + s * eta) / (g * g * g)


@njit(cache=True)
def hugoniot_eta(k0, s, pressure):
    """eta(p) of the module docstring: the compression at which p_H reaches p (p / K0 for
    p <= 0)."""
    if not pressure > 0.0:
        return pressure / k0
    # The form without cancellation or overflow (r = K0 / p)
    r = k0 / pressure
    return 2.0 / (2.0 * s + r + math.sqrt(r * r + 4.0 * s * r))


@njit(cache=True)
def eos_row(p, s0, s1, s3, dv, out):
    """The parameter row for a step of volumetric strain increment dv from the stress with
    normal components (s0, s1, s3): p itself without an EOS, else ``out`` holding p with the
    secant bulk modulus of the step along p_H (module docstring)."""
    if not p[EOS_S] > 0.0:
        return p
    k0 = p[BULK]
    s = p[EOS_S]
    pn = -(s0 + s1 + s3) / 3.0
    for i in range(p.shape[0]):
        out[i] = p[i]
    # The volume the pressure belongs to, moved by the step; the pressure there
    eta = 1.0 - (1.0 - hugoniot_eta(k0, s, pn)) * math.exp(dv)
    pe = hugoniot_pressure(k0, s, min(eta, ETA_MAX / s))
    if pe - pn != 0.0 and dv != 0.0:
        out[BULK] = (pn - pe) / dv
    else:
        out[BULK] = hugoniot_bulk(k0, s, pn)
    return out


@njit(cache=True)
def reference_eta(k0, s, g, pr):
    """The compression at which p_r(eta) = p_H(eta) (1 - g eta / 2) equals pr (module
    docstring; g = Gamma0 < 2 s): the root below 1/s of p_r(eta) = pr, in the form without
    cancellation. g = 0 gives hugoniot_eta."""
    if not pr > 0.0:
        # Tension: K0 eta (1 - g eta / 2) = pr
        return 2.0 * pr / (k0 + math.sqrt(k0 * k0 - 2.0 * g * k0 * pr))
    # Compression: (pr s^2 + K0 g / 2) eta^2 - (K0 + 2 pr s) eta + pr = 0
    return 2.0 * pr / (k0 + 2.0 * s * pr + math.sqrt(k0 * (k0 + 2.0 * pr * (2.0 * s - g))))


@njit(cache=True)
def point_compression(p, s0, s1, s3, e):
    """The compression eta of a point with the Mie-Gruneisen form (module docstring): normal
    stresses (s0, s1, s3), internal energy e per reference volume; the root of
    p_r(eta) = p - Gamma0 e (reference_eta)."""
    pn = -(s0 + s1 + s3) / 3.0
    return reference_eta(p[BULK], p[EOS_S], p[EOS_G], pn - p[EOS_G] * e)


@njit(cache=True)
def gruneisen_row(p, s0, s1, s3, dv, e, q, out):
    """The parameter row ``out`` for a step of volumetric strain increment dv of a point with
    the Mie-Gruneisen form (module docstring): normal stresses (s0, s1, s3), internal energy
    e per reference volume, bulk viscosity q >= 0 of its element. Returns (out, J, dq): the
    secant bulk modulus that takes a volumetric step to the form's pressure at eta_{n+1} with
    the pressure's and the viscosity's work, J = 1 - eta at mid-step, and the viscosity's work
    per reference volume dq = J q max(-dv, 0)."""
    k0 = p[BULK]
    s = p[EOS_S]
    g = p[EOS_G]
    pn = -(s0 + s1 + s3) / 3.0
    for i in range(p.shape[0]):
        out[i] = p[i]
    # The compression the state belongs to, moved by the step
    eta_n = reference_eta(k0, s, g, pn - g * e)
    eta = min(1.0 - (1.0 - eta_n) * math.exp(dv), ETA_MAX / s)
    deta = eta - eta_n
    jmid = 1.0 - 0.5 * (eta_n + eta)
    dq = jmid * q * max(-dv, 0.0)
    # p_{n+1} = p_r(eta) + g (e + (p_n + p_{n+1}) deta / 2 + dq), solved for p_{n+1}
    pe = (hugoniot_pressure(k0, s, eta) * (1.0 - 0.5 * g * eta)
          + g * (e + 0.5 * pn * deta + dq)) / (1.0 - 0.5 * g * deta)
    if pe - pn != 0.0 and dv != 0.0:
        out[BULK] = (pn - pe) / dv
    else:
        out[BULK] = hugoniot_bulk(k0, s, pn)
    return out, jmid, dq


@njit(cache=True)
def gruneisen_heat(p, s, m_old, w, dv, jmid, dq, st):
    """After the material's update of a point with the Mie-Gruneisen form: the step's energy,
    J w + dq (w the trapezoidal stress work per current volume, dq the viscosity's from
    gruneisen_row), into the last column of the state row st, and the pressure rise of the
    deviatoric part of w at constant volume, Gamma0 J w_dev, onto the stress s (4,) whose mean
    stress before the step was m_old."""
    m_new = (s[0] + s[1] + s[3]) / 3.0
    wdev = w - 0.5 * (m_old + m_new) * dv
    st[st.shape[0] - 1] += jmid * w + dq
    dp = p[EOS_G] * jmid * wdev
    s[0] -= dp
    s[1] -= dp
    s[3] -= dp


@njit(cache=True)
def wave_speed(p, sig, e):
    """P-wave speed sqrt((K + 4G/3) / rho0) [m/s] of element e with stresses sig (ne, nip, 4):
    with an EOS, K is the largest bulk modulus of its points' pressures."""
    k = p[BULK]
    if p[EOS_S] > 0.0:
        for q in range(sig.shape[1]):
            pq = -(sig[e, q, 0] + sig[e, q, 1] + sig[e, q, 3]) / 3.0
            k = max(k, hugoniot_bulk(p[BULK], p[EOS_S], pq))
    return math.sqrt((k + 4.0 * p[SHEAR] / 3.0) / p[RHO])
