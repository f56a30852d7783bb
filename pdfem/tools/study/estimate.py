"""The converged estimate of a quantity from a mesh ladder, with its uncertainty.

A grain's mesh at level l has elements of size h proportional to 1/l, so a ladder of levels is
a sequence of meshes with refinement ratios l(k+1)/l(k) that need not be equal (4/3 from
level 3 to 4). For each element rule the study has Q at each level; this module estimates the
value at h -> 0 by Richardson extrapolation with the order the ladder itself shows:

- **Three or more levels**: the last three (h1 > h2 > h3, values q1, q2, q3). If the two
  differences have the same sign, the observed order p solves

      (q2 - q1) / (q3 - q2) = (h1^p - h2^p) / (h2^p - h3^p)

  (bisection; the right side grows with p from ln(h1/h2) / ln(h2/h3)). p is held within
  [P_MIN, P_FORMAL]: a ladder that converges more slowly than P_MIN is treated as if at
  P_MIN (a larger correction and uncertainty), and one that looks faster than the element's
  formal order 2 is not trusted beyond it. The estimate is q3 + (q3 - q2) h3^p / (h2^p -
  h3^p), and its uncertainty the correction |q_inf - q3| times the safety factor 1.25 of a
  three-mesh study (Roache's grid convergence index; Celik et al., J. Fluids Eng. 130,
  078001, 2008, give the procedure for unequal ratios). If the differences change sign the
  ladder oscillates: the estimate is the middle of the last three values and the
  uncertainty 1.25 times half their range.
- **Two levels**: the formal order 2 and the safety factor 3 of a two-mesh study.
- A quantity with a statistical error in the finest run (the front speed's standard error
  over the grains' passages) adds twice that error in quadrature.

The rules' estimates are then combined. If their bands overlap, the combined value is their
inverse-variance weighted mean (the bands taken as two standard deviations); if they do not,
the rules disagree beyond what either ladder shows: the combined value is their midpoint and
its uncertainty reaches both bands (half the distance plus the larger band), and the
disagreement is reported.
"""

import math

# Bounds on the observed order, the element's formal order, the safety factors
P_MIN, P_FORMAL = 0.5, 2.0
SAFETY_3, SAFETY_2 = 1.25, 3.0


def observed_order(h, q):
    """Order p of the last three points of a ladder (h descending, q their values): the root
    of (q2 - q1) / (q3 - q2) = (h1^p - h2^p) / (h2^p - h3^p); 0 when the differences do not
    shrink fast enough for any positive p, None when they change sign or vanish."""
    (h1, h2, h3), (q1, q2, q3) = h[-3:], q[-3:]
    e21, e32 = q2 - q1, q3 - q2
    if e21 * e32 <= 0.0:
        return None
    ratio = e21 / e32

    def f(p):
        return (h1 ** p - h2 ** p) / (h2 ** p - h3 ** p)

    lo, hi = 1e-6, 50.0
    # Below the p -> 0 limit no positive order fits
    if ratio <= f(lo):
        return 0.0
    if ratio >= f(hi):
        return hi
    # Bisection on the monotone ratio
    for _ in range(200):
        mid = 0.5 * (lo + hi)
        if f(mid) < ratio:
            lo = mid
        else:
            hi = mid
    return 0.5 * (lo + hi)


def _extrapolated(h, q, p):
    """Value at h -> 0 of the last two points of a ladder converging at order p."""
    return q[-1] + (q[-1] - q[-2]) * h[-1] ** p / (h[-2] ** p - h[-1] ** p)


def ladder_estimate(levels, values, se=0.0):
    """Converged estimate of one rule's ladder: a dict with ``value``, ``uncertainty``,
    ``order`` (the observed one, None when oscillating or from two levels), ``order_used``,
    ``how`` (words) and ``levels`` (those used); None when fewer than two finite points.
    ``se``: standard error of the finest finite value (added as 2 se)."""
    pts = [(lv, v) for lv, v in sorted(zip(levels, values, strict=True)) if math.isfinite(v)]
    if len(pts) < 2:
        return None
    h = [1.0 / lv for lv, _ in pts]
    q = [v for _, v in pts]
    if len(pts) == 2:
        p_obs, p = None, P_FORMAL
        value = _extrapolated(h, q, p)
        unc, how = SAFETY_2 * abs(value - q[-1]), "two levels, order 2 assumed"
    else:
        p_obs = observed_order(h, q)
        if p_obs is None and q[-1] == q[-2] == q[-3]:
            value, unc, p, how = q[-1], 0.0, None, "the same on the last three levels"
        elif p_obs is None:
            lo, hi = min(q[-3:]), max(q[-3:])
            value, unc, p = 0.5 * (lo + hi), SAFETY_3 * 0.5 * (hi - lo), None
            how = "oscillating: middle of the last three"
        else:
            p = min(max(p_obs, P_MIN), P_FORMAL)
            value = _extrapolated(h, q, p)
            unc = SAFETY_3 * abs(value - q[-1])
            if p_obs == 0.0:
                how = f"differences not shrinking, order {p:.2f} assumed"
            else:
                how = f"observed order {p_obs:.2f}" + (f", used {p:.2f}"
                                                       if abs(p - p_obs) > 5e-3 else "")
    if se and math.isfinite(se):
        unc = math.hypot(unc, 2.0 * se)
    return {"value": value, "uncertainty": unc, "order": p_obs,
            "order_used": p, "how": how, "levels": [lv for lv, _ in pts[-3:]]}


def combine(estimates):
    """One estimate from the rules' (a dict rule -> ladder_estimate or None): ``value``,
    ``uncertainty``, ``agree`` (False when two bands do not overlap) and ``rules`` (those
    used); None when no rule has one."""
    est = {r: e for r, e in estimates.items() if e is not None}
    if not est:
        return None
    vals = [e["value"] for e in est.values()]
    uncs = [e["uncertainty"] for e in est.values()]
    lo = max(v - u for v, u in zip(vals, uncs, strict=True))
    hi = min(v + u for v, u in zip(vals, uncs, strict=True))
    if lo <= hi:
        # Inverse-variance mean (a band of two standard deviations); an exact one dominates
        floor = 1e-12 * max(abs(v) for v in vals) or 1e-300
        w = [1.0 / max(u, floor) ** 2 for u in uncs]
        value = sum(wi * v for wi, v in zip(w, vals, strict=True)) / sum(w)
        unc = 1.0 / math.sqrt(sum(w)) if len(w) > 1 else uncs[0]
        agree = True
    else:
        value = 0.5 * (max(vals) + min(vals))
        unc = 0.5 * (max(vals) - min(vals)) + max(uncs)
        agree = False
    return {"value": value, "uncertainty": unc, "agree": agree, "rules": sorted(est)}


def converged(rows, quantities, se_keys=None):
    """The converged estimate of each quantity from the level x rule grid rows (``setting``
    with ``level``, ``rule`` and ``axis`` "grid"; the quantities' values under their keys):
    a dict key -> {"rules": {rule: ladder_estimate}, "combined": combine(...)}. ``se_keys``
    maps a quantity's key to the row key of its standard error."""
    se_keys = se_keys or {}
    grid = [r for r in rows if r["setting"].axis == "grid" and r["status"] == "ok"]
    out = {}
    for key in quantities:
        per_rule = {}
        for rule in sorted({r["setting"].rule for r in grid}):
            rs = sorted((r for r in grid if r["setting"].rule == rule and math.isfinite(r[key])),
                        key=lambda r: r["setting"].level)
            se = rs[-1].get(se_keys[key], 0.0) if rs and key in se_keys else 0.0
            per_rule[rule] = ladder_estimate([r["setting"].level for r in rs],
                                             [r[key] for r in rs], se)
        out[key] = {"rules": per_rule, "combined": combine(per_rule)}
    return out
