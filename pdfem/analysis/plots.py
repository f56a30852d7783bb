"""PNG figures of a shock run: snapshots, gauges, x-t diagram, Hugoniot, velocity sweep.

Stresses are drawn compressive-positive (-sigma_yy) in MPa, times in microseconds and
lengths in millimetres. Every figure is written atomically (``path.part`` then renamed).
"""

import os

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from matplotlib.collections import PolyCollection  # noqa: E402

US, MM, MPA = 1e6, 1e3, 1e-6


def _save(fig, path, grid_axes=()):
    """Grid and legend on ``grid_axes``; write ``fig`` to ``path`` as PNG atomically, close."""
    for a in grid_axes:
        a.grid(alpha=0.3)
        a.legend(fontsize=8)
    tmp = path + ".part"
    fig.savefig(tmp, format="png", dpi=120, bbox_inches="tight")
    plt.close(fig)
    os.replace(tmp, path)


def _mesh_panel(ax, x, conn, values, norm, cmap):
    """Draw every element of the mesh as a polygon coloured by ``values``; return the artist."""
    pc = PolyCollection(x[conn] * MM, array=values, cmap=cmap, norm=norm, edgecolors="face",
                        linewidths=0.2)
    ax.add_collection(pc)
    ax.set_aspect("equal")
    ax.autoscale_view()
    ax.set_xticks([])
    return pc


def snapshots_plot(frames, conn, path, box=None):
    """Element stress (and temperature) panels of a few frames.

    ``frames``: list of (t, x (NN, 2), comp (NE,) compressive stress in Pa, temp (NE,) or None).
    """
    n = len(frames)
    heat = all(f[3] is not None for f in frames)
    rows = 2 if heat else 1
    fig, axes = plt.subplots(rows, n, figsize=(1.9 * n + 1.2, 5.2 * rows), squeeze=False,
                             sharey=True)
    # One colour scale for all panels: 0 to the 99.5th percentile of the shown stresses
    allc = np.concatenate([f[2] for f in frames]) * MPA
    vmax = max(float(np.percentile(allc, 99.5)), 1e-9)
    norm = matplotlib.colors.Normalize(vmin=0.0, vmax=vmax)
    for i, (t, x, comp, _) in enumerate(frames):
        pc = _mesh_panel(axes[0, i], x, conn, comp * MPA, norm, "inferno")
        axes[0, i].set_title(f"t = {t * US:.2f} us", fontsize=9)
    fig.colorbar(pc, ax=axes[0, :].tolist(), label="-sigma_yy [MPa]", extend="both",
                 fraction=0.04)
    axes[0, 0].set_ylabel("y [mm]")
    # Second row: element temperature (mean of its nodes)
    if heat:
        allt = np.concatenate([f[3] for f in frames])
        tn = matplotlib.colors.Normalize(vmin=float(allt.min()), vmax=float(allt.max()) + 1e-9)
        for i, (_, x, _, temp) in enumerate(frames):
            pt = _mesh_panel(axes[1, i], x, conn, temp, tn, "coolwarm")
        fig.colorbar(pt, ax=axes[1, :].tolist(), label="T [K]", fraction=0.04)
        axes[1, 0].set_ylabel("y [mm]")
    # Same window for every panel: the domain box when given
    if box is not None:
        for ax in axes.ravel():
            ax.set_xlim(box[0] * MM, box[2] * MM)
            ax.set_ylim(box[1] * MM, box[3] * MM)
    _save(fig, path)


def gauges_plot(t, hammer, anvil, path):
    """Hammer and anvil gauges: -v_y and -sigma_yy vs time (``hammer``/``anvil``: dicts
    with ``velocity`` (G, 2) and ``stress`` (G, 4) as stored)."""
    fig, (a1, a2) = plt.subplots(2, 1, figsize=(6.4, 6.0), sharex=True)
    for name, g, c in (("hammer", hammer, "C0"), ("anvil", anvil, "C3")):
        a1.plot(t * US, -g["velocity"][:, 1], c, lw=1.0, label=name)
        a2.plot(t * US, -g["stress"][:, 1] * MPA, c, lw=1.0, label=name)
    a1.set_ylabel("-v_y [m/s]")
    a2.set_ylabel("-sigma_yy [MPa] (compression > 0)")
    a2.set_xlabel("t [us]")
    _save(fig, path, (a1, a2))


def xt_plot(time, grain_y, y_f, fit, y_top0, hammer_y, anvil_y, path):
    """x-t diagram: grain centroid heights, the front, its fit, hammer and anvil faces."""
    fig, ax = plt.subplots(figsize=(6.4, 5.2))
    ax.plot(time * US, grain_y * MM, color="0.6", lw=0.5)
    ax.plot(time * US, hammer_y * MM, "C0", lw=1.5, label="hammer face")
    ax.plot(time * US, anvil_y * MM, "C3", lw=1.5, label="anvil face")
    ax.plot(time * US, y_f * MM, "k.", ms=3, label="front")
    # The fitted front line over its window
    if np.isfinite(fit["us"]):
        tw = np.array([fit["t_start"], fit["t_end"]])
        yw = y_top0 - (fit["us"] * tw + fit["intercept"])
        ax.plot(tw * US, yw * MM, "C2-", lw=2.0, label=f"fit Us = {fit['us']:.0f} m/s")
    ax.set_xlabel("t [us]")
    ax.set_ylabel("y [mm]")
    ax.legend(fontsize=8, loc="lower left")
    ax.grid(alpha=0.3)
    _save(fig, path)


def hugoniot_plot(ev, stress, path, snow=None, measured=None, decel=None):
    """Bed stress vs volumetric strain; ``snow``/``measured``: (e_v, stress in Pa) points;
    ``decel``: optional per-frame stress from the hammer's deceleration."""
    fig, ax = plt.subplots(figsize=(6.0, 4.6))
    ax.plot(ev, stress * MPA, "C0.-", ms=3, lw=0.8, label="bed (mean of the gauges)")
    if decel is not None:
        ax.plot(ev, decel * MPA, "C1-", lw=0.8, alpha=0.8, label="hammer deceleration m dv/dt")
    if snow is not None and np.all(np.isfinite(snow)):
        ax.plot(snow[0], snow[1] * MPA, "rs", ms=8, label="snowplow (measured up)")
    if measured is not None and np.all(np.isfinite(measured)):
        ax.plot(measured[0], measured[1] * MPA, "k^", ms=8, label="front window mean")
    ax.set_xlabel("volumetric strain 1 - H/H0")
    ax.set_ylabel("-sigma_yy [MPa] (compression > 0)")
    ax.legend(fontsize=8)
    ax.grid(alpha=0.3)
    _save(fig, path)


def sweep_plot(points, path):
    """Velocity sweep: Us vs up and stress vs density, ours against the snowplow bound.

    ``points``: dicts with velocity, us, up, sigma, rho0, rho1, solid_density (SI).
    """
    def col(key):
        return np.array([np.nan if p.get(key) is None else float(p[key]) for p in points])

    up, us, sig, rho0, rho1, rhos = (col(k) for k in
                                     ("up", "us", "sigma", "rho0", "rho1", "solid_density"))
    fig, (a1, a2) = plt.subplots(1, 2, figsize=(10.0, 4.4))
    a1.plot(up, us, "C0o", label="DFEM")
    # Snowplow line at the sweep's mean bed and solid densities
    r0, rs = np.nanmean(rho0), np.nanmean(rhos)
    ul = np.linspace(0.0, 1.1 * np.nanmax(np.append(up, 1.0)), 50)
    a1.plot(ul, ul / (1.0 - r0 / rs), "r-", label="snowplow Us = up/(1 - rho0/rho_s)")
    a1.set_xlabel("up [m/s]")
    a1.set_ylabel("Us [m/s]")
    a2.plot(rho1, sig * MPA, "C0o", label="DFEM")
    a2.plot(rhos, rho0 * up / (1.0 - rho0 / rhos) * up * MPA, "rs",
            label="snowplow rho0 Us up at rho_s")
    a2.set_xlabel("density behind the front [kg/m^3]")
    a2.set_ylabel("stress [MPa] (compression > 0)")
    _save(fig, path, (a1, a2))
