"""Compaction front, jump conditions and the bed's Hugoniot from plain arrays.

Heights y are upward; the hammer moves down, so depths and speeds below are positive downward
and stresses are compressive-positive (-sigma_yy). Undefined results are NaN, never errors.
The grains "behind the front" (the shocked grains) at a frame are those whose centroid lies
between the front y_f and the hammer face.
"""

import math

import numpy as np

NAN = float("nan")


def bed_geometry(grain_top0, hammer_y0, anvil_y0, diameter, tol=0.05):
    """Initial bed top, bottom and height H0.

    The top is the hammer face unless the hammer starts more than ``tol`` grain diameters
    above the highest grain node; then the highest grain node (``top_from`` says which).
    """
    gap = float(hammer_y0 - grain_top0)
    if gap > tol * diameter:
        top, src = float(grain_top0), f"highest grain node (hammer {gap:.3g} m above it)"
    else:
        top, src = float(hammer_y0), "hammer face"
    return {"y_top0": top, "y_bottom0": float(anvil_y0), "H0": top - float(anvil_y0),
            "top_from": src, "gap": gap}


def first_below(time, y, level):
    """First time the series y comes down to ``level`` (linear between the last frame above
    and the first at or below); NaN if never."""
    below = np.flatnonzero(y <= level)
    if below.size == 0:
        return NAN
    k = below[0]
    if k == 0:
        return float(time[0])
    y0, y1 = y[k - 1], y[k]
    return float(time[k - 1] + (y0 - level) / (y0 - y1) * (time[k] - time[k - 1]))


def impact_time(time, hammer_y, y_top0):
    """Time at which the hammer face first reaches the bed top (interpolated); NaN if never."""
    return first_below(time, hammer_y, y_top0)


def _front_one(gy, gu, gm, yh, ya, thr, layer):
    """Front height at one frame by scanning layers down from the hammer face."""
    nl = max(int(np.ceil((yh - ya) / layer)), 1)
    j = np.clip(np.floor((yh - gy) / layer).astype(np.int64), 0, nl - 1)
    m = np.bincount(j, weights=gm, minlength=nl)
    mu = np.bincount(j, weights=gm * gu, minlength=nl)
    last, bad = None, None
    # Walk down: skip empty layers, stop at the first that moves slower than the threshold
    for i in np.flatnonzero(m > 0):
        if mu[i] / m[i] > thr:
            last = i
        else:
            bad = i
            break
    if last is None:
        return yh
    if bad is None:
        return ya
    # Threshold crossing between the two layer centres
    c0, c1 = yh - (last + 0.5) * layer, yh - (bad + 0.5) * layer
    u0, u1 = mu[last] / m[last], mu[bad] / m[bad]
    return float(np.clip(c0 + (thr - u0) / (u1 - u0) * (c1 - c0), ya, yh))


def front_positions(time, grain_y, grain_vy, grain_mass, hammer_y, hammer_vy, anvil_y,
                    y_top0, layer, fraction=0.5):
    """Front height y_f (F,), depth d = y_top0 - y_f, and the shocked-grain mask (F, ng).

    A layer (thickness ``layer``, stacked down from the current hammer face) is shocked when
    its grains' mass-weighted downward velocity exceeds ``fraction`` times the hammer face's
    downward speed; the front is the threshold crossing below the lowest shocked layer
    contiguous with the hammer. Before impact y_f is the bed top. The front is a first
    arrival: it never moves back up (a decelerating or rebounding hammer leaves it where the
    disturbance got to), so y_f is the running minimum of the per-frame detections.
    """
    nf = len(time)
    t_imp = impact_time(time, hammer_y, y_top0)
    yf = np.full(nf, float(y_top0))
    for k in range(nf):
        speed = -hammer_vy[k]
        if not (time[k] >= t_imp) or not speed > 0:
            continue
        top = min(hammer_y[k], y_top0)
        yf[k] = min(_front_one(grain_y[k], -grain_vy[k], grain_mass, hammer_y[k], anvil_y[k],
                               fraction * speed, layer), top)
    # First arrival: the front only moves down
    yf = np.minimum.accumulate(yf)
    shocked = (grain_y > yf[:, None]) & (grain_y < hammer_y[:, None])
    return {"y_f": yf, "depth": y_top0 - yf, "shocked": shocked, "t_impact": t_imp}


def passage_times(time, grain_vy, speed):
    """First time each grain's downward velocity reaches ``speed`` (linear between frames);
    NaN for a grain that never does. (ng,)"""
    u = -np.asarray(grain_vy, float)
    hit = u >= speed
    out = np.full(u.shape[1], NAN)
    for i in np.flatnonzero(hit.any(axis=0)):
        k = int(np.argmax(hit[:, i]))
        if k == 0:
            out[i] = time[0]
            continue
        a0, a1 = u[k - 1, i] - speed, u[k, i] - speed
        out[i] = time[k - 1] + (0.0 - a0) / (a1 - a0) * (time[k] - time[k - 1])
    return out


def front_fit(depth0, tpass, H0, lo=0.15, hi=0.85):
    """Front speed from the grains' first passages: least squares of t_i = d_i / Us + t0 over
    the grains whose initial centroid depth d_i lies in [lo, hi] H0 (the material ahead of the
    front is at rest, so Us is the front's speed in the lab). Time is the regressed
    variable: the scatter is in the passage times, the depths are exact.

    Returns us, its standard error ``se``, ``t0``, the grains used ``n`` and those of the
    window that never passed (``missing``), the rms scatter of the passage times, the times
    t_start and t_end at which the fitted front passes lo H0 and hi H0, and ``passed``: at
    least half of the grains in the window's deepest quarter were passed within the run (the
    front crossed the window; grains closer to the anvil may be stopped by it before the front
    reaches them, and a grain pushed aside into a pore may never reach the speed: such grains
    are left out). us is NaN with ``reason`` when fewer than 4 grains qualify.
    """
    d0, tp = np.asarray(depth0, float), np.asarray(tpass, float)
    win = (d0 >= lo * H0) & (d0 <= hi * H0)
    last = win & (d0 >= (hi - 0.25 * (hi - lo)) * H0)
    ok = win & np.isfinite(tp)
    out = {"us": NAN, "se": NAN, "t0": NAN, "n": int(ok.sum()),
           "missing": int((win & ~np.isfinite(tp)).sum()), "rms": NAN, "t_start": NAN,
           "t_end": NAN, "lo": lo, "hi": hi, "reason": "",
           "passed": bool(last.any() and np.mean(np.isfinite(tp[last])) >= 0.5)}
    if ok.sum() < 4:
        out["reason"] = (f"only {ok.sum()} grain(s) between {lo:.0%} and {hi:.0%} of the bed "
                         "height were passed (need 4)")
        return out
    (slope, t0), cov = np.polyfit(d0[ok], tp[ok], 1, cov=True)
    if not slope > 0:
        out["reason"] = "the passage times do not grow with depth"
        return out
    rms = np.sqrt(np.mean((tp[ok] - slope * d0[ok] - t0) ** 2))
    out.update(us=float(1.0 / slope), se=float(np.sqrt(cov[0, 0]) / slope ** 2),
               t0=float(t0), rms=float(rms), t_start=float(t0 + slope * lo * H0),
               t_end=float(t0 + slope * hi * H0))
    return out


def steady_front(depth0, tpass, H0, tol, lo=0.15, hi=0.85):
    """A front speed only for a front that crossed the whole window and was not seen to
    change speed.

    Fits :func:`front_fit` over lo-hi of the bed height and over its two halves; their
    difference is judged against ``tol`` times the whole window's speed and against twice
    its standard error s (from the fits' scatter):

    - ``steadiness = "steady"``: the halves agree within tol, and s is within tol (a change
      of tol would have shown);
    - ``"unresolved"``: the halves agree within 2 s but s exceeds tol (a narrow bed's scatter
      hides a change of tol): fitted, and said so;
    - ``"unsteady"``: the halves differ by more than tol and more than 2 s, or the front did
      not cross the window within the run: ``us`` is NaN and ``reason`` says why
      ("no steady front: ...").

    The halves' speeds and the whole window's fit (``us_fit``) are reported either way.
    """
    mid = 0.5 * (lo + hi)
    fit = front_fit(depth0, tpass, H0, lo, hi)
    early, late = front_fit(depth0, tpass, H0, lo, mid), front_fit(depth0, tpass, H0, mid, hi)
    out = dict(fit, us_fit=fit["us"], us_early=early["us"], us_late=late["us"],
               se_early=early["se"], se_late=late["se"], steadiness="unsteady")
    diff = abs(early["us"] - late["us"])
    noise = np.hypot(early["se"], late["se"])
    if not fit["passed"]:
        deepest = np.nanmax(np.where(np.isfinite(tpass), depth0, np.nan)) / H0 \
            if np.isfinite(tpass).any() else 0.0
        out["reason"] = (f"no steady front: it did not cross {hi:.0%} of the bed height within "
                         f"the run (deepest grain passed at {deepest:.0%})")
    elif not (np.isfinite(fit["us"]) and np.isfinite(diff)):
        out["reason"] = f"no steady front: {fit['reason'] or early['reason'] or late['reason']}"
    elif diff <= tol * fit["us"] and noise <= tol * fit["us"]:
        out["steadiness"] = "steady"
    elif diff <= 2.0 * noise:
        out["steadiness"] = "unresolved"
        out["reason"] = (f"steadiness not resolved: the halves' speeds {early['us']:.0f} and "
                         f"{late['us']:.0f} m/s carry a standard error of {noise:.0f} m/s in "
                         f"their difference, more than {tol:.0%} of the speed")
    else:
        out["reason"] = (f"no steady front: {early['us']:.0f} m/s over {lo:.0%}-{mid:.0%} of "
                         f"the bed height, {late['us']:.0f} m/s over {mid:.0%}-{hi:.0%} (they "
                         f"differ by more than {tol:.0%} and than twice their standard error "
                         f"{noise:.0f} m/s)")
    out["steady"] = out["steadiness"] != "unsteady"
    if not out["steady"]:
        out["us"] = NAN
    return out


def first_rise(t, comp, frac=0.1):
    """First time the compressive series ``comp`` exceeds ``frac`` of its peak; NaN if never."""
    if comp.size == 0 or not np.nanmax(comp) > 0:
        return NAN
    return float(t[np.flatnonzero(comp > frac * np.nanmax(comp))[0]])


def window_mean(t, series, t0, t1):
    """Time average of ``series`` over [t0, t1] (trapezoids on the samples inside); NaN if none."""
    if not (np.isfinite(t0) and np.isfinite(t1)):
        return NAN
    sel = (t >= t0) & (t <= t1)
    if sel.sum() == 0:
        return NAN
    if sel.sum() == 1 or t1 <= t0:
        return float(np.mean(series[sel]))
    ts, ss = t[sel], series[sel]
    return float(np.sum(0.5 * (ss[1:] + ss[:-1]) * np.diff(ts)) / (ts[-1] - ts[0]))


def shocked_state(frames, grain_y, grain_vy, grain_mass, hammer_y, hammer_vy, y_f, width,
                  behind=0.0):
    """Window means of up (downward velocity of the grains between the hammer face and
    ``behind`` above the front, counted by centroid: the compacted state, without the
    front's own rise), rho1 (their mass over that band's area), and the hammer speed."""
    ups, rhos = [], []
    for k in frames:
        lo = y_f[k] + behind
        sel = (grain_y[k] > lo) & (grain_y[k] < hammer_y[k])
        m = grain_mass[sel]
        if m.sum() <= 0 or hammer_y[k] <= lo:
            continue
        ups.append(np.sum(m * -grain_vy[k][sel]) / m.sum())
        rhos.append(m.sum() / (width * (hammer_y[k] - lo)))
    hs = float(np.mean(-hammer_vy[frames])) if len(frames) else NAN
    return {"up": float(np.mean(ups)) if ups else NAN,
            "rho1": float(np.mean(rhos)) if rhos else NAN, "hammer_speed": hs}


def jump_closures(rho0, rho1, us, up, sigma):
    """Jump-condition closures as fractions (NaN where undefined): mass
    |rho0 Us - rho1 (Us - up)| / (rho0 Us); the same in strain form |up/Us - (1 - rho0/rho1)|
    / (1 - rho0/rho1), far more sensitive to up; momentum |sigma - rho0 Us up| / the larger."""
    rho0, rho1, us, up, sigma = (np.float64(v) for v in (rho0, rho1, us, up, sigma))
    with np.errstate(invalid="ignore", divide="ignore"):
        mass = abs(rho0 * us - rho1 * (us - up)) / (rho0 * us)
        strain = 1.0 - rho0 / rho1
        mass_strain = abs(up / us - strain) / strain
        mom = abs(sigma - rho0 * us * up) / np.fmax(sigma, rho0 * us * up)
    return {"mass": float(mass), "mass_strain": float(mass_strain), "momentum": float(mom)}


def grain_compression(sigma, material):
    """Volumetric compression eta = 1 - V/V0 of a grain of ``material`` (a materials table) at
    a mean stress sigma [Pa, compressive]: along the crystal's Hugoniot with eos = "us_up",
    else sigma / K of its linear bulk modulus (1 or more where that cannot hold sigma)."""
    from pdfem.kernels.eos import hugoniot_eta

    k0 = float(material["bulk"])
    if material.get("eos") == "us_up":
        return float(hugoniot_eta(k0, float(material["eos_s"]), float(sigma)))
    return float(sigma) / k0


def compacted_density(sigma, rho_s, material):
    """The densest a bed of grains of ``material`` (a materials table, crystal density rho_s)
    is behind a front of stress sigma [Pa, compressive]: every pore closed and every grain at
    the compression its own bulk response gives at a mean stress sigma
    (:func:`grain_compression`), less the cap's largest plastic compaction W. NaN where a
    linear bulk modulus cannot hold sigma. With strength the grains' mean stress is below the
    front's axial stress, and over grains at unequal stresses the mean compression is below the
    compression at the mean stress (a stiffening response), so a bed behind a steady front is
    no denser than this."""
    w = float(material.get("W", 0.0)) if material.get("model") == "cap" else 0.0
    eta = grain_compression(sigma, material)
    return float(rho_s / ((1.0 - eta) * (1.0 - w))) if eta < 1.0 else NAN


def crystal_bound(up, sigma, us, us_se, rho0, rho1, rho_s, material):
    """The bound of a bed compacted to :func:`compacted_density` at the measured stress:
    rho1 <= rho_max and Us >= up / (1 - rho0/rho_max); whether the measured front keeps it
    (Us within one standard error of its bound counts as kept); kept is None where no front
    was measured (Us, up or rho1 not finite): nothing to check."""
    rho_max = compacted_density(sigma, rho_s, material)
    us_min = up / (1.0 - rho0 / rho_max) if rho_max > rho0 else NAN
    measured = all(math.isfinite(float(q)) for q in (up, us, rho1))
    return {"rho1_max": rho_max, "us_min": float(us_min),
            "kept": bool(rho1 <= rho_max and us + us_se >= us_min) if measured else None}


def snowplow(up, rho0, rho_s):
    """Snowplow (full-compaction) wave for particle velocity up: Us, sigma, rho1 = rho_s."""
    us = up / (1.0 - rho0 / rho_s) if rho0 < rho_s else NAN
    return {"us": float(us), "sigma": float(rho0 * us * up), "rho1": float(rho_s)}


def elastic_speed(material):
    """Bar-wave bound c = sqrt((K + 4G/3)/rho) of a materials table; NaN without K and G."""
    if "bulk" not in material or "shear" not in material:
        return NAN
    return float(np.sqrt((material["bulk"] + 4.0 * material["shear"] / 3.0)
                         / material["density"]))


def frame_means(time, gauge_time, series):
    """Means of a gauge ``series`` over each frame's interval (half-way to its neighbours).

    A box filter one frame interval wide: sampling a ringing gauge at the frame times alone
    would alias the ringing into the frame series.
    """
    gt, gs = np.asarray(gauge_time, float), np.asarray(series, float)
    if gt.size < 2 or len(time) < 2:
        return np.interp(time, gt, gs) if gt.size else np.full(len(time), NAN)
    cum = np.concatenate([[0.0], np.cumsum(0.5 * (gs[1:] + gs[:-1]) * np.diff(gt))])
    mid = 0.5 * (time[1:] + time[:-1])
    a = np.clip(np.concatenate([[time[0]], mid]), gt[0], gt[-1])
    b = np.clip(np.concatenate([mid, [time[-1]]]), gt[0], gt[-1])
    with np.errstate(invalid="ignore", divide="ignore"):
        m = (np.interp(b, gt, cum) - np.interp(a, gt, cum)) / (b - a)
    return np.where(b > a, m, np.interp(time, gt, gs))


def deceleration_stress(time, hammer_vy, hammer_mass, width, frames):
    """Face stress from the hammer's momentum: (m/W) dv_y/dt, compressive-positive, the
    least-squares slope over ``frames`` (NaN with fewer than two). Independent of the ringing
    of a thin hammer's gauge.
    """
    if len(frames) < 2:
        return NAN
    return float(hammer_mass / width * np.polyfit(time[frames], hammer_vy[frames], 1)[0])


def hugoniot(time, hammer_y, anvil_y, H0, gauge_time, hammer_comp, anvil_comp, rho0):
    """Whole-bed Hugoniot per frame: volumetric strain, mean gauge stress, density.

    The stress is the mean of the hammer and anvil gauges, each averaged over the frame's
    interval (:func:`frame_means`).
    """
    H = np.minimum(hammer_y - anvil_y, H0)
    ev = 1.0 - H / H0
    stress = 0.5 * (frame_means(time, gauge_time, hammer_comp)
                    + frame_means(time, gauge_time, anvil_comp))
    with np.errstate(divide="ignore"):
        dens = rho0 / (1.0 - ev)
    return {"ev": ev, "stress": stress, "density": dens}


def bed_stress(run, frames, shocked, y_f):
    """Compressive stress -sigma_yy behind the front, read in the bed itself: the integral of
    the shocked grains' stress over their area divided by the area between the front and the
    hammer face (the pores carry none), averaged over ``frames``. NaN without frames or
    stresses."""
    from pdfem.tools.analysis.runfile import element_areas

    vals = []
    grain_elem = run.elem_body < run.ng
    for k in frames:
        x, comp, _ = run.frame(int(k))
        if comp is None:
            return NAN
        sel = grain_elem.copy()
        sel[grain_elem] = shocked[k][run.elem_body[grain_elem]]
        area = element_areas(x, run.conn)[sel]
        region = run.width * (run.hammer_y[k] - y_f[k])
        if area.sum() > 0 and region > 0:
            vals.append(float((area * comp[sel]).sum() / region))
    return float(np.mean(vals)) if vals else NAN
