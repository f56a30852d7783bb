"""Summary of a shock run: front speed, jump conditions, snowplow bound, figures, JSON + text.

Compressive stresses are quoted as positive numbers (-sigma_yy of the Cauchy stress).
"""

import json
import math

import numpy as np

from pdfem.tools.analysis import compaction as cp
from pdfem.tools.analysis import front as fr
from pdfem.tools.analysis.escape import contact_reach, escape_depths
from pdfem.tools.analysis.interpenetration import nodes_inside_interiors
from pdfem.tools.analysis.jsontext import plain, write_atomic
from pdfem.tools.analysis.report import report_text
from pdfem.tools.analysis.reshock import reshock
from pdfem.tools.analysis.runfile import read_run

NAN = float("nan")
# The files analyse writes after its prefix: the summary always, the figures with plots = "png"
SUMMARY_SUFFIXES = ("-summary.json", "-summary.txt")
FIGURE_SUFFIXES = ("-snapshots.png", "-gauges.png", "-xt.png", "-hugoniot.png")


def output_files(prefix, plots="png", thermal=False):
    """Paths of the files :func:`analyse` writes for ``prefix`` ([shock].plots = ``plots``);
    with ``thermal`` (the frames hold temperatures) those of the hot-spot census too."""
    from pdfem.tools.analysis.hotwrite import output_files as census_files

    out = [prefix + s for s in SUMMARY_SUFFIXES + (FIGURE_SUFFIXES if plots == "png" else ())]
    if thermal:
        out += census_files(prefix, "png" if plots == "png" else "none", shock=True)
    return out


def thermal_fields(fields):
    """Whether frame fields named ``fields`` hold temperatures (the census reads them)."""
    return any(n in fields for n in ("element_temperature", "temperature"))


def _momentum(run, fit, frames, sig_bed, t, hcomp):
    """Stresses behind the front over the fit window: from the piston's contact force (a
    driven hammer), the hammer's deceleration (a free one), the bed, the hammer gauge; and
    which one the momentum check uses."""
    t0, t1 = fit["t_start"], fit["t_end"]
    hg = run.gauges[run.shock["hammer_gauge"]]
    out = {"sigma_piston": cp.piston_stress(t, run.gauge_time, hg.get("force"), run.width,
                                            t0, t1),
           "sigma_hammer_deceleration": fr.deceleration_stress(
               run.time, run.hammer_mean_vy, run.hammer_mass, run.width, frames),
           "sigma_bed": sig_bed, "sigma_gauge": fr.window_mean(t, hcomp, t0, t1)}
    driven = run.drive["driven"] and math.isfinite(out["sigma_piston"])
    out["sigma_source"] = "piston force" if driven else "hammer deceleration"
    out["sigma"] = out["sigma_piston"] if driven else out["sigma_hammer_deceleration"]
    return out


def compute(run):
    """All the numbers of a :class:`~pdfem.tools.analysis.runfile.Run`: (summary dict, arrays)."""
    sh, t = run.shock, run.time
    rho_s, frac = float(sh["solid_density"]), float(sh["front_fraction"])
    # Bed geometry and the initial bed density
    diam = float(np.mean(run.grain_diam))
    geo = fr.bed_geometry(run.grain_top0, run.hammer_y[0], run.anvil_y[0], diam)
    H0 = geo["H0"]
    rho0 = float(run.grain_mass.sum() / (run.width * H0))
    # Compaction front (first passage of frac x the impact speed) and precursor (first
    # motion): per-grain passage times, fitted against the grains' initial depths
    v0 = float(-run.hammer_vy[0])
    depth0 = geo["y_top0"] - run.grain_y[0]
    tol = float(sh["steady_tolerance"])
    fit = fr.steady_front(depth0, fr.passage_times(t, run.grain_vy, frac * v0), H0, tol)
    pfit = fr.steady_front(depth0, fr.passage_times(
        t, run.grain_vy, float(sh["precursor_fraction"]) * v0), H0, tol)
    us = fit["us"]
    # The front in the lab (layer scan, for the figures and the arrival) and its fitted line
    args = (t, run.grain_y, run.grain_vy, run.grain_mass, run.hammer_y, run.hammer_vy,
            run.anvil_y, geo["y_top0"], diam)
    fp, pp = fr.front_positions(*args, frac), fr.front_positions(
        *args, float(sh["precursor_fraction"]))
    y_line = geo["y_top0"] - us * (t - fit["t0"])
    frames = np.flatnonzero((t >= fit["t_start"]) & (t <= fit["t_end"]))
    # Arrival at the bottom: the fitted front at H0, the detected front at the lowest layer's
    # centre, the anvil gauge's rise
    reach = geo["y_bottom0"] + 0.5 * diam
    arr_front, arr_pre = fr.first_below(t, fp["y_f"], reach), fr.first_below(t, pp["y_f"],
                                                                               reach)
    hg, ag = run.gauges[sh["hammer_gauge"]], run.gauges[sh["anvil_gauge"]]
    hcomp, acomp = -hg["stress"][:, 1], -ag["stress"][:, 1]
    arr_fit = fit["t0"] + H0 / us if us > 0 else NAN
    arr_gauge = fr.first_rise(run.gauge_time, acomp, 0.1)
    # Compacted state over the window, from one layer behind the fitted front to the hammer
    st = fr.shocked_state(frames, run.grain_y, run.grain_vy, run.grain_mass, run.hammer_y,
                          run.hammer_vy, y_line, run.width, diam)
    up, rho1 = st["up"], st["rho1"]
    band = (run.grain_y > y_line[:, None] + diam) & (run.grain_y < run.hammer_y[:, None])
    sig_bed = fr.bed_stress(run, frames, band, y_line + diam)
    mom = _momentum(run, fit, frames, sig_bed, run.gauge_time, hcomp)
    jc = fr.jump_closures(rho0, rho1, us, up, mom["sigma"])
    closures = {k: fr.jump_closures(rho0, rho1, us, up, mom[k])["momentum"]
                for k in ("sigma_piston", "sigma_hammer_deceleration", "sigma_bed",
                          "sigma_gauge")}
    snow, snow0 = fr.snowplow(up, rho0, rho_s), fr.snowplow(v0, rho0, rho_s)
    # The bed compacted to its grains' own compression at the measured stress
    bound = fr.crystal_bound(up, mom["sigma"], us, fit["se"], rho0, rho1, rho_s,
                             run.scene["materials"][run.grain_material])
    # The wave reflected at the anvil against the limits of the compacted bed's reshock
    h_rise = float(np.interp(arr_gauge, t, run.hammer_y - run.anvil_y)) \
        if np.isfinite(arr_gauge) else NAN
    rsh = reshock(run.gauge_time, acomp, arr_gauge, run.drive, h_rise, up, rho1, mom["sigma"],
                  rho_s, run.scene["materials"][run.grain_material])
    # How much of the grains' area lies in folded corners, over the front's window and at the
    # end (a mesh folded over itself is denser than any material in it)
    folded = run.folded[frames] if frames.size else run.folded[-1:]
    # Grain nodes that have passed into another grain's interior elements by the end, where no
    # contact acts (pdfem.tools.analysis.interpenetration)
    gsel = run.elem_body < run.ng
    inside = nodes_inside_interiors(run.frame(len(run.time) - 1)[0], run.conn[gsel],
                                    run.elem_body[gsel], run.node_body)
    interp = float(inside.sum()) / max(1, int(np.count_nonzero(run.node_body < run.ng)))
    # Grain nodes farther beyond the anvil, the hammer or the box's sides than contact reaches
    # (pdfem.tools.analysis.escape)
    dom = run.scene["domain"]
    esc = escape_depths(run.grain_bottom, run.grain_top, run.grain_xrange, run.anvil_y,
                        run.hammer_y, dom["box"], dom.get("periodic", "none") == "x")
    reach = contact_reach(run.scene)
    escaped = {k: esc[k] for k in ("below_anvil", "above_hammer", "past_sides")}
    far = max(("below_anvil", "above_hammer"), key=escaped.get)
    k = int(np.argmax(run.escaped_mass))
    escaped.update(reach=reach, escaped=escaped[far] > reach,
                   t_escaped=float(run.time[esc[far + "_frame"]]),
                   mass=float(run.escaped_mass[k]), t_mass=float(run.time[k]),
                   mass_end=float(run.escaped_mass[-1]))
    comp = cp.compaction(t, run.grain_y, run.grain_mass, run.anvil_y, run.hammer_y,
                         run.grain_top, H0)
    # The whole bed's Hugoniot from the faces: a driven (rigid) hammer's face stress is the
    # bed's push on it; a free hammer's, its gauge
    face = hg["force"][:, 1] / run.width if run.drive["driven"] and hg.get("force") is not None \
        else hcomp
    hug = fr.hugoniot(t, run.hammer_y, run.anvil_y, H0, run.gauge_time, face, acomp, rho0)
    # The 1997 report's numbers against the snowplow bound at its own density
    rref, usref = float(sh["reference_density"]), sh["reference_us"]
    rsref = float(sh.get("reference_solid_density", rho_s))
    bal = run.energy.get("balance_error")
    dr = run.drive
    summary = {
        "file": run.path,
        "bed": {"H0": H0, "top_from": geo["top_from"], "width": run.width,
                "n_grains": run.ng, "grain_mass": float(run.grain_mass.sum()),
                "mean_grain_diameter": diam, "rho0": rho0, "phi0": rho0 / rho_s,
                "reference_density": rref, "solid_density": rho_s,
                "grain_material": run.grain_material},
        "drive": {"kind": "piston" if dr["driven"] else "hammer", "impact_speed": v0,
                  "release": dr["release"], "ramp_down": dr["ramp_down"],
                  "face_deviation": cp.drive_deviation(
                      t, run.hammer_vy, v0, arr_fit if np.isfinite(arr_fit) else arr_front)},
        "front": {"us": us, "se": fit["se"], "steady": fit["steady"],
                  "steadiness": fit["steadiness"], "note": fit["reason"],
                  "us_fit": fit["us_fit"], "fit_t_start": fit["t_start"],
                  "fit_t_end": fit["t_end"], "fit_grains": fit["n"],
                  "fit_missing": fit["missing"],
                  "fit_depth_range": [fit["lo"] * H0, fit["hi"] * H0], "fit_rms": fit["rms"],
                  "front_fraction": frac, "layer": diam, "us_early": fit["us_early"],
                  "us_late": fit["us_late"], "se_early": fit["se_early"],
                  "se_late": fit["se_late"], "t_impact": fp["t_impact"],
                  "arrival_front": arr_front, "arrival_fit": arr_fit,
                  "arrival_gauge": arr_gauge},
        "precursor": {"us": pfit["us"], "se": pfit["se"], "steady": pfit["steady"],
                      "steadiness": pfit["steadiness"],
                      "note": pfit["reason"], "us_fit": pfit["us_fit"],
                      "us_early": pfit["us_early"], "us_late": pfit["us_late"],
                      "se_early": pfit["se_early"], "se_late": pfit["se_late"],
                      "fraction": float(sh["precursor_fraction"]),
                      "arrival": arr_pre, "arrival_fit": pfit["t0"] + H0 / pfit["us"]},
        "shocked": {"up": up, "hammer_speed": st["hammer_speed"], "rho1": rho1,
                    "rho0_us_up": rho0 * us * up,
                    "momentum_ahead": cp.momentum_ahead(frames, run.grain_y, run.grain_vy,
                                                        run.grain_mass, y_line), **mom},
        "jump": {"mass_closure": jc["mass"], "mass_strain_closure": jc["mass_strain"],
                 "momentum_closure": jc["momentum"],
                 "momentum_closure_piston": closures["sigma_piston"],
                 "momentum_closure_deceleration": closures["sigma_hammer_deceleration"],
                 "momentum_closure_bed": closures["sigma_bed"],
                 "momentum_closure_gauge": closures["sigma_gauge"]},
        "snowplow": {"us": snow["us"], "sigma": snow["sigma"], "rho1": snow["rho1"],
                     "us_at_impact_speed": snow0["us"]},
        "bound": {**bound, "sigma": mom["sigma"]},
        "reshock": rsh,
        "mesh": {"folded_front": float(np.max(folded)), "folded_end": float(run.folded[-1]),
                 "folded_max": float(np.max(run.folded)), "interpenetrated_end": interp,
                 "escape": escaped},
        "compaction": {k: comp[k] for k in ("peak", "t_peak", "final", "t_final", "kept",
                                            "peak_height", "final_height")},
        "gauges": {"hammer_peak": float(np.max(hcomp)) if hcomp.size else NAN,
                   "anvil_peak": float(np.max(acomp)) if acomp.size else NAN},
        "elastic_wave_speed": fr.elastic_speed(run.scene["materials"][run.grain_material]),
        "energy": {"balance_error_last": float(bal[-1]) if bal is not None and bal.size else NAN,
                   "balance_error_max": (float(np.max(np.abs(bal)))
                                         if bal is not None and bal.size else NAN)},
        "reference": {"us": usref, "arrival": sh["reference_arrival"], "density": rref,
                      "solid_density": rsref, "impact_speed": v0,
                      "us_min_at_impact_speed": v0 / (1.0 - rref / rsref),
                      "up_max_at_reference_us": usref * (1.0 - rref / rsref),
                      "up_allowed_by_our_us": us * (1.0 - rho0 / rho_s)},
        "hugoniot": {"final_strain": float(hug["ev"][-1]),
                     "final_density": float(hug["density"][-1]),
                     "crystal": sh.get("crystal_hugoniot")},
        "notes": list(run.notes),
    }
    arrays = {"time": t, "y_f": fp["y_f"], "y_p": pp["y_f"], "y_line": y_line, "fit": fit,
              "precursor_fit": pfit, "geo": geo, "hugoniot": hug, "compaction": comp["strain"]}
    return summary, arrays


def _figures(run, s, arrays, prefix, sweep=None):
    """Draw the four figures of a run next to ``prefix`` (``sweep``: a sweep's JSON, whose
    points and static curve join the jump-state figure)."""
    from pdfem.tools.analysis import plots

    t, fit = arrays["time"], arrays["fit"]
    sh = run.shock
    # Snapshots: five frames from the first impact to the end
    if run.has_stress:
        t0 = s["front"]["t_impact"]
        k0 = int(np.searchsorted(t, t0)) if t0 is not None and math.isfinite(t0) else 0
        ks = np.unique(np.linspace(min(k0, len(t) - 1), len(t) - 1, 5).round().astype(int))
        frames = [(t[k], *run.frame(k)) for k in ks]
        dom = run.scene["domain"]
        plots.snapshots_plot(frames, run.conn, prefix + "-snapshots.png", box=dom["box"],
                             periodic=dom.get("periodic", "none") == "x")
    plots.gauges_plot(run.gauge_time, run.gauges[sh["hammer_gauge"]],
                      run.gauges[sh["anvil_gauge"]], prefix + "-gauges.png", width=run.width)
    plots.xt_plot(t, run.grain_y, arrays["y_f"], fit, arrays["geo"]["y_top0"], run.hammer_y,
                  run.anvil_y, prefix + "-xt.png", y_p=arrays["y_p"])
    plots.jump_plot(jump_state(run, s, sweep), prefix + "-hugoniot.png", sweep=sweep)


def jump_state(run, s, sweep=None):
    """What :func:`pdfem.tools.analysis.plots.jump_plot` draws of a summary ``s``: the
    measured jump state, the snowplow's, and the bound curve (:func:`front.compacted_density`
    of the grains' material) up to twice the largest stress shown."""
    b, h, f = s["bed"], s["shocked"], s["front"]
    sigmas = [h["sigma"], s["snowplow"]["sigma"]]
    if sweep is not None:
        sigmas += [p["sigma"] for p in sweep.get("points", []) if p.get("sigma") is not None]
    top = 2.0 * max([q for q in sigmas if q is not None and math.isfinite(q)] + [1.0e6])
    grid = np.linspace(0.0, top, 120)
    mat = run.scene["materials"][run.grain_material]
    dens = np.array([fr.compacted_density(q, b["solid_density"], mat) for q in grid])
    us = f["us"] if f["us"] is not None else NAN
    se = f["se"] if f["se"] is not None and math.isfinite(f["se"]) else 0.0
    return {"rho0": b["rho0"], "rho_s": b["solid_density"], "us": us, "us_se": se,
            "up": h["up"], "rho1": h["rho1"],
            "sigma": h["sigma"], "snow_sigma": s["snowplow"]["sigma"],
            "rho1_max": s["bound"]["rho1_max"], "bound": (dens, grid)}


def analyse(run_path, prefix, extra=None, sweep=None):
    """Analyse the shock run at ``run_path``; write ``<prefix>-summary.json``/``.txt`` and the
    figures (with ``[shock].plots = "png"``); return the summary dict.

    ``extra`` (e.g. wall times, packing from the preparation) is merged under ``"run"``. The
    returned dict also holds ``"arrays"`` (front and Hugoniot time series), not in the JSON.
    Raises :class:`pdfem.errors.InputError` for an unreadable file or one without [shock].
    """
    run = read_run(str(run_path))
    summary, arrays = compute(run)
    summary["run"] = dict(extra or {})
    plots = run.shock.get("plots", "png")
    if _holds_temperatures(run_path):
        summary["hotspots"] = _census(run_path, prefix, plots)
    doc = plain(summary)
    write_atomic(prefix + "-summary.json", json.dumps(doc, indent=1) + "\n")
    write_atomic(prefix + "-summary.txt", report_text(doc))
    if plots == "png":
        _figures(run, summary, arrays, prefix, sweep)
    return {**summary, "arrays": arrays}


def _holds_temperatures(path):
    import h5py

    with h5py.File(path, "r") as f:
        return thermal_fields(f["frames"])


def _census(path, prefix, plots):
    """The hot-spot census of a thermal shock run, its files written next to the summary;
    the summary's part: the last frame behind the front and the most spots of any frame."""
    from pdfem.tools.analysis.hotcensus import census
    from pdfem.tools.analysis.hotwrite import write_outputs

    result, maps = census(str(path))
    write_outputs(result, maps, prefix, "png" if plots == "png" else "none")
    last = result["frames"][-1]
    region = last.get("shocked", last["whole"])
    most = max(result["frames"], key=lambda fr: fr["whole"]["n_spots"])
    keys = ("mean", "p50", "p90", "p99", "p99.9", "max", "n_spots")
    return {"time": last["time"], "spot_threshold": result["settings"]["spot_threshold"],
            "shocked": {k: region[k] for k in keys},
            "area_fraction": region["area_fraction"],
            "most_spots": most["whole"]["n_spots"], "most_spots_time": most["time"],
            "heat_fields": result["heat_fields"]}
