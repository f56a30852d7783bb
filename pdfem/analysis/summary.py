"""Summary of a shock run: front speed, jump conditions, snowplow bound, figures, JSON + text.

Compressive stresses are quoted as positive numbers (-sigma_yy of the Cauchy stress).
"""

import json
import math
import os

import numpy as np

from pdfem.analysis import front as fr
from pdfem.analysis.runfile import read_run

NAN = float("nan")
# The files analyse writes after its prefix: the summary always, the figures with plots = "png"
SUMMARY_SUFFIXES = ("-summary.json", "-summary.txt")
FIGURE_SUFFIXES = ("-snapshots.png", "-gauges.png", "-xt.png", "-hugoniot.png")


def output_files(prefix, plots="png"):
    """Paths of the files :func:`analyse` writes for ``prefix`` ([shock].plots = ``plots``)."""
    return [prefix + s for s in SUMMARY_SUFFIXES + (FIGURE_SUFFIXES if plots == "png" else ())]


def _plain(v):
    """JSON-ready copy: numpy scalars to floats/ints, NaN/inf to None, arrays to lists."""
    if isinstance(v, dict):
        return {str(k): _plain(x) for k, x in v.items()}
    if isinstance(v, (list, tuple, np.ndarray)):
        return [_plain(x) for x in v]
    if isinstance(v, (bool, np.bool_)):
        return bool(v)
    if isinstance(v, (int, np.integer)):
        return int(v)
    if isinstance(v, (float, np.floating)):
        return float(v) if math.isfinite(v) else None
    return v


def _write(path, text):
    """Write ``text`` to ``path`` atomically."""
    with open(path + ".part", "w") as f:
        f.write(text)
    os.replace(path + ".part", path)


def compute(run):
    """All the numbers of a :class:`~pdfem.analysis.runfile.Run`: (summary dict, arrays)."""
    sh, t = run.shock, run.time
    rho_s, frac = float(sh["solid_density"]), float(sh["front_fraction"])
    # Bed geometry and the initial bed density
    diam = float(np.mean(run.grain_diam))
    geo = fr.bed_geometry(run.grain_top0, run.hammer_y[0], run.anvil_y[0], diam)
    H0 = geo["H0"]
    rho0 = float(run.grain_mass.sum() / (run.width * H0))
    # Front positions, Us fit, arrival at the bottom
    fp = fr.front_positions(t, run.grain_y, run.grain_vy, run.grain_mass, run.hammer_y,
                            run.hammer_vy, run.anvil_y, geo["y_top0"], diam, frac)
    fit = fr.fit_front(t, fp["depth"], H0)
    # Steadiness: separate fits over the upper and lower halves of the window
    early, late = fr.fit_front(t, fp["depth"], H0, 0.15, 0.5), fr.fit_front(t, fp["depth"], H0,
                                                                             0.5, 0.85)
    hg, ag = run.gauges[sh["hammer_gauge"]], run.gauges[sh["anvil_gauge"]]
    hcomp, acomp = -hg["stress"][:, 1], -ag["stress"][:, 1]
    arr_fit = (H0 - fit["intercept"]) / fit["us"] if fit["us"] > 0 else NAN
    arr_gauge = fr.first_rise(run.gauge_time, acomp, 0.1)
    # State behind the front over the fit window
    st = fr.shocked_state(fit["frames"], run.grain_vy, run.grain_mass, fp["shocked"],
                          run.hammer_y, run.hammer_vy, fp["y_f"], run.width)
    up, rho1 = st["up"], st["rho1"]
    sigma = fr.window_mean(run.gauge_time, hcomp, fit["t_start"], fit["t_end"])
    jc = fr.jump_closures(rho0, rho1, fit["us"], up, sigma)
    # Cross-check of sigma from the whole hammer's deceleration (no gauge ringing)
    sig_dec = fr.deceleration_stress(t, run.hammer_mean_vy, run.hammer_mass, run.width,
                                     fit["frames"])
    jc_dec = fr.jump_closures(rho0, rho1, fit["us"], up, sig_dec)
    # The stress behind the front read in the shocked grains themselves
    sig_bed = fr.bed_stress(run, fit["frames"], fp["shocked"], fp["y_f"])
    jc_bed = fr.jump_closures(rho0, rho1, fit["us"], up, sig_bed)
    snow = fr.snowplow(up, rho0, rho_s)
    hug = fr.hugoniot(t, run.hammer_y, run.anvil_y, H0, run.gauge_time, hcomp, acomp, rho0)
    # The 1997 report's numbers against the snowplow bound at its own density
    v0, rref, usref = float(-run.hammer_vy[0]), float(sh["reference_density"]), sh["reference_us"]
    rsref = float(sh.get("reference_solid_density", rho_s))
    bal = run.energy.get("balance_error")
    summary = {
        "file": run.path,
        "bed": {"H0": H0, "top_from": geo["top_from"], "width": run.width,
                "n_grains": run.ng, "grain_mass": float(run.grain_mass.sum()),
                "mean_grain_diameter": diam, "rho0": rho0, "phi0": rho0 / rho_s,
                "reference_density": rref, "solid_density": rho_s,
                "grain_material": run.grain_material},
        "front": {"us": fit["us"], "fit_t_start": fit["t_start"], "fit_t_end": fit["t_end"],
                  "fit_frames": fit["n"], "fit_depth_range": [fit["lo"] * H0, fit["hi"] * H0],
                  "fit_note": fit["reason"], "fit_rms": fit["rms"], "front_fraction": frac,
                  "layer": diam, "us_early": early["us"], "us_late": late["us"],
                  "t_impact": fp["t_impact"], "arrival_fit": arr_fit,
                  "arrival_gauge": arr_gauge},
        "shocked": {"up": up, "hammer_speed": st["hammer_speed"], "rho1": rho1,
                    "sigma": sigma, "sigma_hammer_deceleration": sig_dec,
                    "sigma_bed": sig_bed,
                    "rho0_us_up": rho0 * fit["us"] * up},
        "jump": {"mass_closure": jc["mass"], "momentum_closure": jc["momentum"],
                 "momentum_closure_deceleration": jc_dec["momentum"],
                 "momentum_closure_bed": jc_bed["momentum"]},
        "snowplow": {"us": snow["us"], "sigma": snow["sigma"], "rho1": snow["rho1"]},
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
                      "up_allowed_by_our_us": fit["us"] * (1.0 - rho0 / rho_s)},
        "hugoniot": {"final_strain": float(hug["ev"][-1]),
                     "final_density": float(hug["density"][-1])},
        "notes": list(run.notes),
    }
    hug["stress_deceleration"] = fr.deceleration_stress(t, run.hammer_mean_vy, run.hammer_mass,
                                                        run.width)
    arrays = {"time": t, "y_f": fp["y_f"], "depth": fp["depth"], "fit": fit, "geo": geo,
              "hugoniot": hug}
    return summary, arrays


def _f(v, scale=1.0, fmt=".1f"):
    """A number scaled and formatted, or 'n/a'."""
    return "n/a" if v is None or not math.isfinite(v) else format(v * scale, fmt)


def _show(v):
    """A run figure for the text report: wall times in seconds to 0.1 s."""
    if isinstance(v, dict):
        return ", ".join(f"{k} {_show(x)}" for k, x in v.items())
    if isinstance(v, float):
        return f"{v:.4g}"
    return str(v)


def report_text(s):
    """The short human-readable report of a summary dict (compression positive)."""
    b, f, h, r = s["bed"], s["front"], s["shocked"], s["reference"]
    fit_line = (f"fit {_f(f['fit_t_start'], 1e6, '.2f')}-{_f(f['fit_t_end'], 1e6, '.2f')} us, "
                f"{f['fit_frames']} frames" if f["us"] is not None and math.isfinite(f["us"])
                else f"no fit: {f['fit_note']}")
    lines = [
        f"Shock run {s['file']}  (stresses compressive-positive)",
        f"bed: H0 = {_f(b['H0'], 1e3, '.3f')} mm (top from {b['top_from']}), width "
        f"{_f(b['width'], 1e3, '.3f')} mm, {b['n_grains']} grains of {b['grain_material']}",
        f"rho0 = {_f(b['rho0'])} kg/m3 (experiment {_f(b['reference_density'])}), "
        f"phi0 = {_f(b['phi0'], 1, '.3f')} of rho_s = {_f(b['solid_density'])}",
        f"front: Us = {_f(f['us'])} m/s ({fit_line}); report {_f(r['us'])} m/s",
        f"  front = layer scan ({_f(f['layer'], 1e3, '.3f')} mm layers = mean grain diameter), "
        f"threshold {f['front_fraction']} x hammer face speed",
        f"  fit depths "
        f"{_f(f['fit_depth_range'][0], 1e3, '.2f')}-{_f(f['fit_depth_range'][1], 1e3, '.2f')} mm,"
        f" rms residual {_f(f['fit_rms'], 1e3, '.3f')} mm; Us over 15-50 % {_f(f['us_early'])}"
        f" m/s, over 50-85 % {_f(f['us_late'])} m/s",
        f"impact at {_f(f['t_impact'], 1e6, '.3f')} us; arrival at the bottom: fit "
        f"{_f(f['arrival_fit'], 1e6, '.2f')} us, anvil gauge {_f(f['arrival_gauge'], 1e6, '.2f')}"
        f" us; report {_f(r['arrival'], 1e6, '.2f')} us",
        f"behind the front: up = {_f(h['up'])} m/s (hammer face {_f(h['hammer_speed'])} m/s), "
        f"rho1 = {_f(h['rho1'])} kg/m3",
        f"hammer gauge stress over the window sigma = {_f(h['sigma'], 1e-6)} MPa; "
        f"rho0 Us up = {_f(h['rho0_us_up'], 1e-6)} MPa; from the hammer's deceleration "
        f"{_f(h['sigma_hammer_deceleration'], 1e-6)} MPa; behind the front (bed) "
        f"{_f(h['sigma_bed'], 1e-6)} MPa",
        f"jump closures: mass {_f(s['jump']['mass_closure'], 100)} %, momentum with the stress "
        f"behind the front {_f(s['jump']['momentum_closure_bed'], 100)} %, with the "
        f"hammer's deceleration {_f(s['jump']['momentum_closure_deceleration'], 100)} %, with "
        f"the hammer gauge {_f(s['jump']['momentum_closure'], 100)} %",
        f"snowplow at the measured up: Us = {_f(s['snowplow']['us'])} m/s, sigma = "
        f"{_f(s['snowplow']['sigma'], 1e-6)} MPa, rho1 = rho_s",
        f"peak gauge stresses: hammer {_f(s['gauges']['hammer_peak'], 1e-6)} MPa, anvil "
        f"{_f(s['gauges']['anvil_peak'], 1e-6)} MPa",
        f"elastic wave speed of the grains sqrt((K+4G/3)/rho) = {_f(s['elastic_wave_speed'])} m/s",
        f"bed at the end: volumetric strain {_f(s['hugoniot']['final_strain'], 1, '.3f')}, "
        f"density {_f(s['hugoniot']['final_density'])} kg/m3",
        f"energy balance error: last {_f(s['energy']['balance_error_last'], 100, '.2f')} %, "
        f"max {_f(s['energy']['balance_error_max'], 100, '.2f')} %",
        "",
        "1997 report: a steady wave with up = "
        f"{_f(r['impact_speed'])} m/s into {_f(r['density'])} kg/m3 of {_f(r['solid_density'])}"
        f" kg/m3 crystal must run at >= up/(1 - rho0/rho_s) = "
        f"{_f(r['us_min_at_impact_speed'])} m/s, so its "
        f"{_f(r['us'])} m/s front implies up <= {_f(r['up_max_at_reference_us'])} m/s.",
        f"This run (2-D bed, rho0/rho_s = {_f(b['phi0'], 1, '.3f')}): Us = {_f(f['us'])} m/s "
        f"with up = {_f(h['up'])} m/s; its Us allows up <= Us (1 - rho0/rho_s) = "
        f"{_f(r['up_allowed_by_our_us'])} m/s.",
    ]
    lines += [f"note: {n}" for n in s["notes"]]
    if s.get("run"):
        lines += ["", "run:"] + [f"  {k}: {_show(v)}" for k, v in s["run"].items()]
    return "\n".join(lines) + "\n"


def _figures(run, s, arrays, prefix):
    """Draw the four figures of a run next to ``prefix``."""
    from pdfem.analysis import plots

    t, fit, hug = arrays["time"], arrays["fit"], arrays["hugoniot"]
    sh = run.shock
    # Snapshots: five frames from the first impact to the end
    if run.has_stress:
        t0 = s["front"]["t_impact"]
        k0 = int(np.searchsorted(t, t0)) if t0 is not None and math.isfinite(t0) else 0
        ks = np.unique(np.linspace(min(k0, len(t) - 1), len(t) - 1, 5).round().astype(int))
        frames = [(t[k], *run.frame(k)) for k in ks]
        plots.snapshots_plot(frames, run.conn, prefix + "-snapshots.png",
                             box=run.scene["domain"]["box"])
    plots.gauges_plot(run.gauge_time, run.gauges[sh["hammer_gauge"]],
                      run.gauges[sh["anvil_gauge"]], prefix + "-gauges.png")
    plots.xt_plot(t, run.grain_y, arrays["y_f"], fit, arrays["geo"]["y_top0"], run.hammer_y,
                  run.anvil_y, prefix + "-xt.png")
    b, sn, h = s["bed"], s["snowplow"], s["shocked"]
    rho0, rho1 = b["rho0"], h["rho1"]
    plots.hugoniot_plot(hug["ev"], hug["stress"], prefix + "-hugoniot.png",
                        decel=hug["stress_deceleration"],
                        snow=(1.0 - rho0 / b["solid_density"], sn["sigma"]),
                        measured=(1.0 - rho0 / rho1 if rho1 > 0 else NAN, h["sigma"]))


def analyse(run_path, prefix, extra=None):
    """Analyse the shock run at ``run_path``; write ``<prefix>-summary.json``/``.txt`` and the
    figures (with ``[shock].plots = "png"``); return the summary dict.

    ``extra`` (e.g. wall times, packing from the preparation) is merged under ``"run"``. The
    returned dict also holds ``"arrays"`` (front and Hugoniot time series), not in the JSON.
    Raises :class:`pdfem.errors.InputError` for an unreadable file or one without [shock].
    """
    run = read_run(str(run_path))
    summary, arrays = compute(run)
    summary["run"] = dict(extra or {})
    plain = _plain(summary)
    _write(prefix + "-summary.json", json.dumps(plain, indent=1) + "\n")
    _write(prefix + "-summary.txt", report_text(plain))
    if run.shock.get("plots", "png") == "png":
        _figures(run, summary, arrays, prefix)
    return {**summary, "arrays": arrays}
