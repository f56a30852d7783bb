"""PNG figures of a shock run: snapshots, gauges, x-t diagram, jump state, velocity sweep.

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


def _mesh_panel(ax, x, conn, values, norm, cmap, box=None, periodic=False):
    """Draw every element of the mesh as a polygon coloured by ``values``; return the artist.
    With periodic sides each element is folded into the box [x0, y0, x1, y1] and drawn again
    one box width to either side, so that what crossed a side shows at the other."""
    poly = x[conn]
    if periodic:
        w = box[2] - box[0]
        poly = poly - (np.floor((poly[:, :, 0].mean(axis=1) - box[0]) / w) * w)[:, None, None] \
            * np.array([1.0, 0.0])
        poly = np.concatenate([poly + np.array([k * w, 0.0]) for k in (-1, 0, 1)])
        values = np.tile(values, 3)
    pc = PolyCollection(poly * MM, array=values, cmap=cmap, norm=norm, edgecolors="face",
                        linewidths=0.2)
    ax.add_collection(pc)
    ax.set_aspect("equal")
    ax.autoscale_view()
    ax.set_xticks([])
    return pc


def snapshots_plot(frames, conn, path, box=None, periodic=False):
    """Element stress (and temperature) panels of a few frames.

    ``frames``: list of (t, x (NN, 2), comp (NE,) compressive stress in Pa, temp (NE,) or None);
    with ``periodic`` (sides periodic in x, ``box`` given) the mesh is drawn folded into the box.
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
        pc = _mesh_panel(axes[0, i], x, conn, comp * MPA, norm, "inferno", box, periodic)
        axes[0, i].set_title(f"t = {t * US:.2f} us", fontsize=9)
    fig.colorbar(pc, ax=axes[0, :].tolist(), label="-sigma_yy [MPa]", extend="both",
                 fraction=0.04)
    axes[0, 0].set_ylabel("y [mm]")
    # Second row: element temperature (mean of its nodes)
    if heat:
        allt = np.concatenate([f[3] for f in frames])
        tn = matplotlib.colors.Normalize(vmin=float(allt.min()), vmax=float(allt.max()) + 1e-9)
        for i, (_, x, _, temp) in enumerate(frames):
            pt = _mesh_panel(axes[1, i], x, conn, temp, tn, "coolwarm", box, periodic)
        fig.colorbar(pt, ax=axes[1, :].tolist(), label="T [K]", fraction=0.04)
        axes[1, 0].set_ylabel("y [mm]")
    # Same window for every panel: the domain box when given
    if box is not None:
        for ax in axes.ravel():
            ax.set_xlim(box[0] * MM, box[2] * MM)
            ax.set_ylim(box[1] * MM, box[3] * MM)
    _save(fig, path)


def gauges_plot(t, hammer, anvil, path, width=None):
    """Hammer and anvil gauges: -v_y and -sigma_yy vs time (``hammer``/``anvil``: dicts
    with ``velocity`` (G, 2), ``stress`` (G, 4) and ``force`` (G, 2) or None as stored);
    with ``width``, also the contact stress on each face (force over the width: all a rigid
    piston shows)."""
    fig, (a1, a2) = plt.subplots(2, 1, figsize=(6.4, 6.0), sharex=True)
    for name, g, c, sign in (("hammer", hammer, "C0", 1.0), ("anvil", anvil, "C3", -1.0)):
        a1.plot(t * US, -g["velocity"][:, 1], c, lw=1.0, label=name)
        a2.plot(t * US, -g["stress"][:, 1] * MPA, c, lw=1.0, label=f"{name} (elements)")
        if width and g.get("force") is not None:
            a2.plot(t * US, sign * g["force"][:, 1] / width * MPA, c, lw=0.8, ls="--",
                    label=f"{name} face (contact force / width)")
    a1.set_ylabel("-v_y [m/s]")
    a2.set_ylabel("-sigma_yy [MPa] (compression > 0)")
    a2.set_xlabel("t [us]")
    _save(fig, path, (a1, a2))


def xt_plot(time, grain_y, y_f, fit, y_top0, hammer_y, anvil_y, path, y_p=None):
    """x-t diagram: grain centroid heights, the compaction front and its fit (steady fronts
    only), the precursor, hammer and anvil faces."""
    fig, ax = plt.subplots(figsize=(6.4, 5.2))
    ax.plot(time * US, grain_y * MM, color="0.6", lw=0.5)
    ax.plot(time * US, hammer_y * MM, "C0", lw=1.5, label="hammer face")
    ax.plot(time * US, anvil_y * MM, "C3", lw=1.5, label="anvil face")
    if y_p is not None:
        ax.plot(time * US, y_p * MM, "C1x", ms=3, label="precursor (first motion)")
    ax.plot(time * US, y_f * MM, "k.", ms=3, label="compaction front")
    # The fitted front line over its window
    if np.isfinite(fit["us"]):
        tw = np.array([fit["t_start"], fit["t_end"]])
        yw = y_top0 - fit["us"] * (tw - fit["t0"])
        ax.plot(tw * US, yw * MM, "C2-", lw=2.0, label=f"fit Us = {fit['us']:.0f} m/s")
    ax.set_xlabel("t [us]")
    ax.set_ylabel("y [mm]")
    ax.legend(fontsize=8, loc="lower left")
    ax.grid(alpha=0.3)
    _save(fig, path)


def jump_plot(jump, path, sweep=None):
    """The run's jump state in the stress-density plane, as a shock physicist reads it: the
    measured state behind the front on its Rayleigh line sigma = rho0 Us^2 (1 - rho0/rho)
    (shaded for Us within one standard error), the snowplow state at the measured up and its
    full density, the bound of grains compressed by their own bulk response at each stress,
    and, from a sweep's JSON (``sweep``: its ``points`` and ``static``), the sweep's steady
    states and the static compression curve.

    ``jump``: rho0, rho_s, us, us_se, up, rho1, sigma, snow_sigma, rho1_max and bound
    (densities, stresses) of the bound curve, SI.
    """
    fig, ax = plt.subplots(figsize=(6.4, 4.8))
    r0, rs, us, se = jump["rho0"], jump["rho_s"], jump["us"], jump["us_se"]
    rho1, sig = jump["rho1"], jump["sigma"]
    dens, stress = jump["bound"]
    rho_hi = np.nanmax([rs, rho1, jump["rho1_max"]]) * 1.03
    rho = np.linspace(r0, rho_hi, 200)
    def ray(u):
        """The Rayleigh line of a front of speed u from the bed at rest [MPa]."""
        return r0 * u * u * (1.0 - r0 / rho) * MPA

    if np.isfinite(us):
        # The Rayleigh line of the measured front, and its band for Us +- one standard error
        ax.fill_between(rho, ray(max(us - se, 0.0)), ray(us + se), color="C0", alpha=0.15,
                        lw=0)
        ax.plot(rho, ray(us), "C0-", lw=1.2, label=f"Rayleigh line, Us = {us:.0f} m/s")
    if np.isfinite(rho1) and np.isfinite(sig):
        ax.plot([rho1], [sig * MPA], "ko", ms=7, label="jump state behind the front")
    ax.axvline(rs, color="r", lw=0.8, ls="--", label="every pore closed, rigid grains")
    if np.isfinite(jump["snow_sigma"]):
        ax.plot([rs], [jump["snow_sigma"] * MPA], "rs", ms=7,
                label=f"snowplow state at up = {jump['up']:.0f} m/s")
    ax.plot(dens, stress * MPA, "C2-", lw=1.2,
            label="bound: grains at their own compression")
    top = [sig, jump["snow_sigma"]]
    if sweep is not None:
        pts = [p for p in sweep.get("points", [])
               if all(p.get(k) is not None and np.isfinite(p[k]) for k in ("us", "rho1", "sigma"))]
        if pts:
            ax.plot([p["rho1"] for p in pts], [p["sigma"] * MPA for p in pts], "C1D", ms=5,
                    mfc="none", label="sweep: steady fronts")
            top += [p["sigma"] for p in pts]
        st = sweep.get("static")
        if st:
            ax.plot(st["density"], np.asarray(st["sigma_piston"]) * MPA, "C4-", lw=1.0,
                    label="static compression (piston)")
    ax.set_xlim(0.95 * r0, rho_hi)
    ax.set_ylim(0.0, 1.6 * np.nanmax(np.append(np.asarray(top, float), 1.0)) * MPA)
    ax.set_xlabel("density [kg/m^3]")
    ax.set_ylabel("stress [MPa] (compression > 0)")
    _save(fig, path, (ax,))


def sweep_plot(points, path, static=None):
    """The bed's compaction Hugoniot: Us and the precursor speed vs up, and stress vs density,
    beside the snowplow bound and the crystal's Hugoniot (``crystal_hugoniot`` [c0, s] of
    the points, when given); ``static``: the static compression curve (density, piston and
    anvil stresses, snowplow floor). Unsteady points (us None) are drawn hollow at their
    unfitted speed.

    ``points``: dicts with velocity, us, us_fit, precursor, up, sigma, rho0, rho1,
    solid_density (SI).
    """
    def col(key):
        return np.array([np.nan if p.get(key) is None else float(p[key]) for p in points])

    up, us, usf, pre, sig, rho0, rho1, rhos = (col(k) for k in (
        "up", "us", "us_fit", "precursor", "sigma", "rho0", "rho1", "solid_density"))
    fig, (a1, a2) = plt.subplots(1, 2, figsize=(11.0, 4.6))
    steady = np.isfinite(us)
    a1.plot(up[steady], us[steady], "C0o", label="compaction front (steady)")
    if (~steady & np.isfinite(usf)).any():
        a1.plot(up[~steady], usf[~steady], "C0o", mfc="none", label="not steady (unfitted)")
    a1.plot(up, pre, "C1x", label="precursor (first motion)")
    # Snowplow line at the sweep's mean bed and solid densities; the crystal's Hugoniot
    r0, rs = np.nanmean(rho0), np.nanmean(rhos)
    ul = np.linspace(0.0, 1.1 * np.nanmax(np.append(up, 1.0)), 50)
    a1.plot(ul, ul / (1.0 - r0 / rs), "r-", label="snowplow Us = up/(1 - rho0/rho_s)")
    crystal = next((p.get("crystal_hugoniot") for p in points if p.get("crystal_hugoniot")),
                   None)
    if crystal:
        c0, sc = crystal
        a1.plot(ul, c0 + sc * ul, "k--", lw=1.0, label=f"crystal Us = {c0:.0f} + {sc:g} up")
    a1.set_xlabel("up [m/s]")
    a1.set_ylabel("Us [m/s]")
    a2.plot(rho1[steady], sig[steady] * MPA, "C0o", label="shock (steady fronts)")
    # Snowplow: full density rho_s at the stress rho0 Us up of the snowplow wave
    a2.plot(np.full(ul.shape, rs), r0 * ul ** 2 / (1.0 - r0 / rs) * MPA, "r-",
            label="snowplow (rho_s, rho0 up^2/(1 - rho0/rho_s))")
    if crystal:
        usc = c0 + sc * ul
        a2.plot(rs * usc / (usc - ul), rs * usc * ul * MPA, "k--", lw=1.0,
                label="crystal Hugoniot")
    if static is not None:
        a2.plot(static["density"], static["sigma_piston"] * MPA, "C2-", lw=1.0,
                label="static compression (piston)")
        a2.plot(static["density"], static["sigma_anvil"] * MPA, "C2:", lw=1.0,
                label="static compression (anvil)")
        a2.axhline(static["floor"] * MPA, color="C2", lw=0.5, ls="--",
                   label="static run's snowplow floor")
    top = np.nanmax(np.append(sig, 1.0)) * MPA
    a2.set_ylim(0.0, 1.3 * top)
    a2.set_xlim(0.9 * r0, max(1.15 * rs, 1.05 * np.nanmax(np.append(rho1, rs))))
    a2.set_xlabel("density [kg/m^3]")
    a2.set_ylabel("stress [MPa] (compression > 0)")
    _save(fig, path, (a1, a2))
