"""The wave reflected at the anvil: a reshock of the compacted bed, measured at the anvil and
bracketed by its grains' bulk response.

Stresses are compressive-positive and velocities downward-positive (towards the anvil), as in
:mod:`pdfem.tools.analysis.front`. The bed behind the compaction front is in state 1 (density
rho1, stress sigma1, moving at u1); the wave reflected from a wall at rest brings it to rest.
Mass and momentum across that reflected shock, seen from the material ahead of it, give the
Rayleigh line

    u1**2 = (sigma2 - sigma1) (1/rho1 - 1/rho2),

so the reflected stress sigma2 depends on how dense the reshocked bed becomes. Two limits of
that density bracket it:

- every pore left behind the front closes and the grains compress along their own bulk
  response at sigma2 (:func:`pdfem.tools.analysis.front.compacted_density`): the densest
  reshocked bed, hence the lowest stress that can stop it, a bound (sigma2 >= sigma_min);
- the pore space left behind the front stays and only the grains compress, from their
  compression at sigma1 to that at sigma2: the stiffest reshock that crushes nothing further,
  an estimate from above (strength ignored: the grains' mean stress is taken as the axial one).
"""

import math

import numpy as np

from pdfem.tools.analysis.front import compacted_density, grain_compression

NAN = float("nan")
# Duration over which the anvil must hold a stress to count as the reflected wave's [s]: three
# ringing periods of the packaged scenes' 0.2 mm steel anvil plate (2 x 0.2 mm / 5.8 km/s)
HOLD = 2.0e-7


def reflected_stress(sigma1, rho1, u1, density_at, top=1.0e13):
    """Stress sigma2 behind a shock that brings material in state (rho1, sigma1, u1) to rest
    against a rigid wall, when its density at stress sigma is ``density_at(sigma)``: the root of
    (sigma2 - sigma1)(1/rho1 - 1/rho2(sigma2)) = u1**2, by bisection between sigma1 and ``top``.
    NaN where the inputs are not finite, u1 <= 0, or no stress up to ``top`` (or up to the
    edge of the range where the material has a density) stops it."""
    if not all(math.isfinite(float(q)) for q in (sigma1, rho1, u1)) or u1 <= 0 or rho1 <= 0:
        return NAN

    def excess(s):
        rho2 = density_at(s)
        if not math.isfinite(rho2):
            return math.inf
        return (s - sigma1) * (1.0 / rho1 - 1.0 / rho2) - u1 * u1

    lo, hi = float(sigma1), float(top)
    if excess(hi) < 0.0:
        return NAN
    # Bisection to a relative width of 1e-12 (excess rises with sigma: the bed stiffens)
    for _ in range(200):
        mid = 0.5 * (lo + hi)
        if excess(mid) < 0.0:
            lo = mid
        else:
            hi = mid
        if hi - lo <= 1.0e-12 * hi:
            break
    # A bracket closing on the edge of the material's range (no density there) is no root
    return 0.5 * (lo + hi) if math.isfinite(excess(hi)) else NAN


def bed_reshock(sigma1, rho1, u1, rho_s, material):
    """The reflected stress of a compacted bed of grains of ``material`` (crystal density
    rho_s) in state (rho1, sigma1, u1), stopped by a rigid anvil: ``sigma_min`` with every pore
    closing (a bound: the anvil's stress is no lower) and ``sigma_pores_kept`` with the pore
    space behind the front kept (an estimate from above). NaN where undefined."""
    eta1 = grain_compression(sigma1, material)

    def pores_kept(s):
        eta2 = grain_compression(s, material)
        return rho1 * (1.0 - eta1) / (1.0 - eta2) if eta2 < 1.0 else NAN

    return {"sigma_min": reflected_stress(sigma1, rho1, u1,
                                          lambda s: compacted_density(s, rho_s, material)),
            "sigma_pores_kept": reflected_stress(sigma1, rho1, u1, pores_kept)}


def anvil_plateau(gauge_time, anvil_comp, t_rise, t_end, width=HOLD):
    """The stress the anvil holds under the reflected wave: the largest time mean of the anvil
    gauge's compressive stress over ``width`` between its rise and ``t_end`` (while the piston
    still drives the bed: its stop reaches the anvil later still), and the gauge's standard
    deviation over that stretch. The mean over a few of the anvil plate's ringing periods
    passes over the ringing and the reflected wave's own rise. NaN where no such stretch
    exists, or where the gauge is still rising: its running mean must come within a tenth of
    that largest one at least 2 ``width`` before ``t_end``."""
    none = {"sigma": NAN, "spread": NAN, "window": [NAN, NAN]}
    t, c = np.asarray(gauge_time, float), np.asarray(anvil_comp, float)
    if not (np.isfinite(t_rise) and np.isfinite(t_end)) or t_end - t_rise < width or t.size < 2:
        return none
    # Running means over [ts, ts + width] for every sample ts of the stretch, from the
    # cumulative trapezoidal integral
    cum = np.concatenate([[0.0], np.cumsum(0.5 * (c[1:] + c[:-1]) * np.diff(t))])
    ts = t[(t >= t_rise) & (t + width <= t_end)]
    if ts.size == 0:
        return none
    means = (np.interp(ts + width, t, cum) - np.interp(ts, t, cum)) / width
    k = int(np.argmax(means))
    # Held, not still rising: within a tenth of it at least one more width before the end
    t90 = ts[np.flatnonzero(means >= 0.9 * means[k])[0]]
    if t90 + 2.0 * width > t_end:
        return none
    sel = (t >= ts[k]) & (t <= ts[k] + width)
    return {"sigma": float(means[k]), "spread": float(np.std(c[sel])),
            "window": [float(ts[k]), float(ts[k] + width)]}


def hold_end(t_rise, drive, height, sigma1, rho1, u1, sigma_fast):
    """Until when the anvil holds the reflected wave's state: NaN unless a piston drives the bed
    (``drive``, as the run file's) and the anvil rises (``t_rise``) before it starts to stop;
    then the earlier of its release and the time the reflected wave needs to reach the piston
    and come back, over the bed's ``height`` at the rise, at the speed of the stiffest reshock
    (stress ``sigma_fast``): D - u1 in the lab, D = (sigma_fast - sigma1)/(rho1 u1). A free
    hammer's reflected state decays as it slows, and a second reshock from the piston is not
    this one."""
    if not (drive["driven"] and math.isfinite(t_rise)
            and t_rise < drive["release"] - drive["ramp_down"]):
        return NAN
    if not all(math.isfinite(float(q)) for q in (height, sigma1, rho1, u1, sigma_fast)) \
            or u1 <= 0.0:
        return NAN
    speed = (sigma_fast - sigma1) / (rho1 * u1) - u1
    back = t_rise + 2.0 * height / speed if speed > 0.0 else math.inf
    return float(min(drive["release"], back))


def reshock(gauge_time, anvil_comp, t_rise, drive, height, up, rho1, sigma1, rho_s, material):
    """The anvil's plateau under the reflected wave (:func:`anvil_plateau` until
    :func:`hold_end`) beside the two limits of :func:`bed_reshock` for the measured state
    behind the front; ``kept`` says whether the plateau is at or above the bound sigma_min
    (within its spread), None where either is undefined."""
    limits = bed_reshock(sigma1, rho1, up, rho_s, material)
    t_end = hold_end(t_rise, drive, height, sigma1, rho1, up, limits["sigma_pores_kept"])
    if len(gauge_time):
        t_end = min(t_end, float(gauge_time[-1]))
    plateau = anvil_plateau(gauge_time, anvil_comp, t_rise, t_end)
    p, lo = plateau["sigma"], limits["sigma_min"]
    kept = bool(p + plateau["spread"] >= lo) if np.isfinite(p) and np.isfinite(lo) else None
    return {**limits, "sigma": p, "spread": plateau["spread"], "window": plateau["window"],
            "kept": kept, "hold_end": t_end}
