"""The bed as a whole during and after a shock: the drive, momentum ahead of the front, and
compaction that stays or springs back.

Heights y are upward and the hammer moves down; velocities and stresses are quoted
downward-positive and compressive-positive, as in :mod:`pdfem.tools.analysis.front`.
"""

import numpy as np

NAN = float("nan")


def drive_deviation(time, hammer_vy, v0, t_until):
    """Largest |hammer face speed - v0| / v0 over the frames up to ``t_until`` (the front's
    arrival at the bottom): how steady the drive was while the wave crossed the bed."""
    sel = time <= t_until if np.isfinite(t_until) else np.ones(len(time), bool)
    if not sel.any() or not v0 > 0:
        return NAN
    return float(np.max(np.abs(-hammer_vy[sel] - v0)) / v0)


def momentum_ahead(frames, grain_y, grain_vy, grain_mass, y_f):
    """Mean over ``frames`` of the share of the bed's downward momentum carried by the grains
    ahead of (below) the compaction front: what the precursor has set moving."""
    shares = []
    for k in frames:
        p = grain_mass * -grain_vy[k]
        total = p.sum()
        if total > 0:
            shares.append(float(p[grain_y[k] < y_f[k]].sum() / total))
    return float(np.mean(shares)) if shares else NAN


def piston_stress(time, gauge_time, force, width, t0, t1):
    """Mean compressive stress on the hammer face over [t0, t1]: the bed's push on the hammer
    gauge's nodes (contact force, N/m, upward positive) over the width; NaN without it."""
    if force is None or not (np.isfinite(t0) and np.isfinite(t1)):
        return NAN
    sel = (gauge_time >= t0) & (gauge_time <= t1)
    if not sel.any():
        return NAN
    return float(np.mean(force[sel, 1]) / width)


def compaction(time, grain_y, grain_mass, anvil_y, hammer_y, grain_top, H0):
    """Compaction strain of the bed per frame, its peak and final values.

    Primary: from the height of the grains' centre of mass above the anvil face, 1 - h/h0
    (for a uniformly compacted bed h = H/2, so this is 1 - H/H0; a few grains thrown off the
    top of a released bed move it by their share of the mass only). Also from the bed height
    H, anvil face to the lower of the hammer face and the highest grain node."""
    h = (grain_y @ grain_mass) / grain_mass.sum() - anvil_y
    e = 1.0 - h / h[0]
    e_h = 1.0 - (np.minimum(hammer_y, grain_top) - anvil_y) / H0
    k = int(np.argmax(e))
    return {"strain": e, "strain_height": e_h, "peak": float(e[k]), "t_peak": float(time[k]),
            "final": float(e[-1]), "t_final": float(time[-1]),
            "kept": float(e[-1] / e[k]) if e[k] > 0 else NAN,
            "peak_height": float(e_h.max()), "final_height": float(e_h[-1])}
