"""Figures of the hot-spot census: temperature maps, the distribution against time, the
spot count and hot area against time, and the front-relative history.

Times in microseconds, lengths in millimetres, temperatures in K. Every figure is written
atomically (``path.part`` then renamed), as PNG or PDF.
"""

import os

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from matplotlib.collections import PolyCollection  # noqa: E402

US, MM = 1e6, 1e3


def _save(fig, path, fmt):
    """Write ``fig`` to ``path`` in ``fmt`` atomically and close it."""
    tmp = path + ".part"
    fig.savefig(tmp, format=fmt, dpi=120, bbox_inches="tight")
    plt.close(fig)
    os.replace(tmp, path)


def _series(result, region, key):
    """Per-frame values of ``key`` in ``region`` (NaN for None)."""
    return np.array([np.nan if f[region][key] is None else f[region][key]
                     for f in result["frames"]], float)


def _marks(ax, result):
    """Vertical lines at the impact and at the front's arrival at the bed bottom."""
    fr = result["front"]
    if fr is None:
        return
    for key, style, name in (("t_impact", ":", "impact"),
                             ("arrival_bottom", "--", "front at the bed bottom")):
        if fr[key] is not None and np.isfinite(fr[key]):
            ax.axvline(fr[key] * US, color="k", ls=style, lw=0.8, label=name)


def map_plot(result, maps, path, fmt):
    """Grain elements coloured by temperature at a few frames, hot spots outlined, blocks
    grey, the front as a dashed line."""
    frames = maps["frames"]
    n = len(frames)
    conn, grain = maps["conn"], maps["grain"]
    fig, axes = plt.subplots(1, n, figsize=(2.0 * n + 1.2, 5.4), squeeze=False, sharey=True)
    allt = np.concatenate([f[3][grain] for f in frames])
    norm = matplotlib.colors.Normalize(vmin=float(allt.min()), vmax=float(allt.max()) + 1e-9)
    front = result["front"]
    for ax, (k, t, x, temp, label) in zip(axes[0], frames, strict=True):
        poly = x[conn] * MM
        ax.add_collection(PolyCollection(poly[~grain], facecolors="0.75", edgecolors="face"))
        pc = PolyCollection(poly[grain], array=temp[grain], cmap="inferno", norm=norm,
                            edgecolors="face", linewidths=0.2)
        ax.add_collection(pc)
        hot = label > 0
        ax.add_collection(PolyCollection(poly[hot], facecolors="none", edgecolors="cyan",
                                         linewidths=0.6))
        if front is not None:
            ax.axhline(front["y_f"][k] * MM, color="w", ls="--", lw=0.8)
        ax.set_title(f"t = {t * US:.2f} us\n{int(label.max())} spot(s)", fontsize=9)
        ax.set_aspect("equal")
        ax.autoscale_view()
        ax.set_xticks([])
    box = maps.get("box")
    if box is not None:
        for ax in axes[0]:
            ax.set_xlim(box[0] * MM, box[2] * MM)
            ax.set_ylim(box[1] * MM, box[3] * MM)
    axes[0, 0].set_ylabel("y [mm]")
    fig.colorbar(pc, ax=axes[0].tolist(), label="T [K]", fraction=0.04)
    _save(fig, path, fmt)


def result_times(result):
    """The frame times of a census result."""
    return [f["time"] for f in result["frames"]]


def distribution_plot(result, path, fmt):
    """Mass-weighted percentile bands of the temperature against time, per region."""
    t = np.array(result_times(result)) * US
    regions = result["regions"]
    fig, axes = plt.subplots(1, len(regions), figsize=(5.6 * len(regions), 4.4), squeeze=False,
                             sharey=True)
    for ax, region in zip(axes[0], regions, strict=True):
        s = {k: _series(result, region, k) for k in ("mean", "p50", "p90", "p99", "p99.9",
                                                     "max")}
        ax.fill_between(t, s["p50"], s["p90"], color="C1", alpha=0.5, label="50-90th")
        ax.fill_between(t, s["p90"], s["p99"], color="C3", alpha=0.4, label="90-99th")
        ax.plot(t, s["mean"], "k-", lw=1.2, label="mean")
        ax.plot(t, s["p99.9"], "C3:", lw=1.0, label="99.9th")
        ax.plot(t, s["max"], "C4--", lw=0.8, label="max")
        _marks(ax, result)
        ax.set_title("whole bed" if region == "whole" else "behind the front", fontsize=10)
        ax.set_xlabel("t [us]")
        ax.grid(alpha=0.3)
        ax.legend(fontsize=7)
    axes[0, 0].set_ylabel("T [K] (mass-weighted percentiles)")
    _save(fig, path, fmt)


def count_plot(result, path, fmt):
    """Hot-spot count and hot area fraction against time."""
    t = np.array(result_times(result)) * US
    fig, (a1, a2) = plt.subplots(2, 1, figsize=(6.4, 6.4), sharex=True)
    thr = result["settings"]["thresholds"]
    for region, ls in (("whole", "-"), ("shocked", "--")):
        if region not in result["regions"]:
            continue
        name = "whole bed" if region == "whole" else "behind the front"
        a1.plot(t, _series(result, region, "n_spots"), "k" + ls, lw=1.0, label=name)
        for i, th in enumerate(thr):
            frac = [f[region]["area_fraction"][float(th)] for f in result["frames"]]
            a2.plot(t, np.array(frac, float), f"C{i}{ls}", lw=1.0, label=f"> {th:g} K, {name}")
    for ax in (a1, a2):
        _marks(ax, result)
        ax.grid(alpha=0.3)
        ax.legend(fontsize=7)
    a1.set_ylabel(f"hot spots (> {result['settings']['spot_threshold']:g} K)")
    a2.set_ylabel("hot area fraction")
    a2.set_xlabel("t [us]")
    _save(fig, path, fmt)


def front_plot(result, path, fmt):
    """Temperature against time since the front arrived: mean and percentiles, and the
    number of elements in each bin."""
    h = result["front_relative"]
    tau = np.array(h["tau"], float) * US
    fig, (a1, a2) = plt.subplots(2, 1, figsize=(6.4, 6.0), sharex=True,
                                 gridspec_kw={"height_ratios": (3, 1)})
    for key, style, name in (("mean", "k-", "mean"), ("p50", "C0-", "50th"),
                             ("p90", "C1-", "90th"), ("p99", "C3-", "99th")):
        a1.plot(tau, np.array(h[key], float), style, lw=1.0, label=name)
    a2.plot(tau, h["n"], "k-", lw=1.0)
    for ax in (a1, a2):
        ax.axvline(0.0, color="k", ls=":", lw=0.8)
        ax.grid(alpha=0.3)
    a1.legend(fontsize=8)
    a1.set_ylabel("T [K] (mass-weighted)")
    a2.set_ylabel("elements")
    a2.set_xlabel("time since the front arrived [us]")
    _save(fig, path, fmt)


def figures(result, maps, prefix, fmt):
    """Every figure of the census next to ``prefix``."""
    map_plot(result, maps, f"{prefix}-hotspots-map.{fmt}", fmt)
    distribution_plot(result, f"{prefix}-hotspots-distribution.{fmt}", fmt)
    count_plot(result, f"{prefix}-hotspots-count.{fmt}", fmt)
    if result["front"] is not None:
        front_plot(result, f"{prefix}-hotspots-front.{fmt}", fmt)
