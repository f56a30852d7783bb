"""The accuracy study's figure: worst error versus wall time with its Pareto front, and the
error of each quantity versus quads per grain (PNG, matplotlib Agg, written atomically)."""

import math

import numpy as np
from matplotlib.ticker import FuncFormatter

from pdfem.tools.analysis.plots import _save, plt
from pdfem.tools.study.quantities import QUANTITIES

# Smallest error drawn on the log axes (an exact match would not show)
FLOOR = 1e-5
MARKERS = {"1pt": "o", "2x2": "s"}
COLOURS = {"grid": "C0", "safety": "C1", "kn0": "C2"}


def _err(v):
    """An error for a log axis: NaN stays (not drawn), tiny ones are lifted to FLOOR."""
    return v if not math.isfinite(v) else max(v, FLOOR)


def _plain_ticks(ax):
    """Log axes labelled with plain numbers at 1, 2 and 5 of each decade: seconds or quads on
    x, percent on y."""
    def label(scale, unit):
        def fmt(v, _):
            lead = v / 10.0 ** math.floor(math.log10(v)) if v > 0 else 0.0
            return f"{v * scale:g}{unit}" if round(lead, 6) in (1.0, 2.0, 5.0) else ""
        return FuncFormatter(fmt)

    for axis, fmt in ((ax.xaxis, label(1.0, "")), (ax.yaxis, label(100.0, " %"))):
        axis.set_major_formatter(fmt)
        axis.set_minor_formatter(fmt)


def accuracy_plot(rows, tol, path, estimate=None, header=None):
    """Left: each run's worst relative error against its wall time, the Pareto front and the
    tolerance; right: each quantity's error against quads per grain for the level x rule
    grid, errors against the converged estimate, and (dotted, with ``estimate``: the
    pdfem.tools.study.estimate.converged dict) each estimate's own relative band. ``header``:
    a line over both (where the figure came from)."""
    fig, (a1, a2) = plt.subplots(1, 2, figsize=(12.5, 5.0))
    fig.subplots_adjust(wspace=0.3)
    if header:
        fig.suptitle(header, fontsize=8)
    # Worst error against wall time, one marker per run
    shown = set()
    for r in rows:
        s = r["setting"]
        if not math.isfinite(r["err_max"]):
            continue
        name = {"grid": f"level x rule ({s.rule})", "safety": f"safety factor ({s.rule})",
                "kn0": f"contact stiffness ({s.rule})"}[s.axis]
        a1.loglog(r["wall_s"], _err(r["err_max"]), MARKERS[s.rule], color=COLOURS[s.axis],
                  ms=7, mfc="none" if s.rule == "1pt" else COLOURS[s.axis],
                  label=None if name in shown else name)
        shown.add(name)
        tag = f"L{s.level}" + (f" s{s.safety:g}" if s.axis == "safety" else "") \
            + (f" k{s.kn0_scale:g}" if s.axis == "kn0" else "")
        a1.annotate(tag, (r["wall_s"], _err(r["err_max"])), fontsize=7,
                    xytext=(4, 3), textcoords="offset points")
    # The Pareto front and the tolerance
    front = sorted((r for r in rows if r["pareto"]), key=lambda r: r["wall_s"])
    if front:
        a1.step([r["wall_s"] for r in front], [_err(r["err_max"]) for r in front], "k-",
                where="post", lw=1.0, alpha=0.6, label="Pareto front")
    a1.axhline(tol, color="C3", ls="--", lw=1.0, label=f"{tol * 100:g} % tolerance")
    a1.set_xlabel("wall time [s]")
    a1.set_ylabel("worst relative error against the converged estimate")
    _plain_ticks(a1)
    failed = [r["setting"].label for r in rows if r["status"] != "ok"]
    a1.set_title("error against cost" + (f"; failed: {', '.join(failed)}" if failed else ""),
                 fontsize=9)
    # Each quantity against quads per grain, one line per rule (the grid runs)
    grid = [r for r in rows if r["setting"].axis == "grid"]
    for q, (key, head, *_) in enumerate(QUANTITIES):
        for rule, ls in (("1pt", "--"), ("2x2", "-")):
            pts = sorted((r["setting"].quads, _err(r["err_" + key])) for r in grid
                         if r["setting"].rule == rule and math.isfinite(r["err_" + key]))
            if pts:
                x, y = np.array(pts).T
                a2.loglog(x, y, ls + MARKERS[rule], color=f"C{q}", ms=5,
                          mfc="none" if rule == "1pt" else f"C{q}",
                          label=f"{head} ({rule})")
    a2.axhline(tol, color="C3", ls="--", lw=1.0)
    # Each estimate's band relative to its value: errors below it are not resolved
    for q, (key, *_) in enumerate(QUANTITIES):
        c = ((estimate or {}).get(key) or {}).get("combined")
        if c and c["value"] and c["uncertainty"] > 0.0:
            a2.axhline(_err(abs(c["uncertainty"] / c["value"])), color=f"C{q}", ls=":",
                       lw=1.0)
    a2.set_xlabel("quads per grain")
    a2.set_ylabel("relative error against the converged estimate")
    _plain_ticks(a2)
    a2.set_title((f"level x rule grid, safety {grid[0]['setting'].safety:g}" if grid else "")
                 + ("; dotted: the estimate's band" if estimate else ""), fontsize=9)
    a2.grid(alpha=0.3)
    a2.legend(fontsize=7, ncol=2)
    _save(fig, path, (a1,))
