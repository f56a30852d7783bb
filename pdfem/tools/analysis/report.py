"""The short text report of a shock run's summary (compression positive): what ``analyse``
prints and writes as ``-summary.txt``."""

import math

from pdfem.tools.analysis.reshock import HOLD

# Share of the grains' area in folded corners above which the summary calls the meshes
# folded over themselves (2 x 2 runs at 1-2 km/s stay below 0.1 %)
FOLDED_LIMIT = 0.01


def _escape_line(e):
    """The text line of the summary's mesh.escape."""
    line = (f"grain nodes at most {_f(e['below_anvil'], 1e6, '.1f')} um below the anvil's "
            f"face and {_f(e['above_hammer'], 1e6, '.1f')} um above the hammer's (contact "
            f"overlap reaches {_f(e['reach'], 1e6, '.1f')} um), "
            + ("periodic sides" if e["past_sides"] is None
               else f"{_f(e['past_sides'], 1e6, '.1f')} um past the box's sides"))
    if e["escaped"]:
        line += (f": grain material has gone past the anvil or the hammer, at most "
                 f"{_f(e['mass'], 100, '.3f')} % of the grains' mass in elements reaching past "
                 f"(at {_f(e['t_mass'], 1e6, '.3f')} us; {_f(e['mass_end'], 100, '.3f')} % at the "
                 "end)" + (", lost to the bed" if e["mass_end"] > 0 else ", all back by the end"))
    return line


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


def _reshock_line(r):
    """The anvil under the reflected wave beside the compacted bed's reshock limits."""
    where = (f"{_f(r['sigma'], 1e-6)} +- {_f(r['spread'], 1e-6)} MPa over "
             f"{_f(r['window'][0], 1e6, '.2f')}-{_f(r['window'][1], 1e6, '.2f')} us"
             if r["sigma"] is not None and math.isfinite(r["sigma"])
             else "not measured (no stress held while a piston drove the bed)")
    return (f"reflected wave at the anvil (a reshock of the compacted bed), the most it holds "
            f"for {_f(HOLD, 1e6, '.1f')} us: {where}; every pore "
            f"closing >= {_f(r['sigma_min'], 1e-6)} MPa: "
            + bound_word(r["kept"], "BROKEN", "n/a")
            + f"; pores kept {_f(r['sigma_pores_kept'], 1e-6)} MPa")


def _speed_line(name, w):
    """'Us = ... m/s (steady, ...)' or the reason there is none, for the front or precursor."""
    if w["us"] is not None and math.isfinite(w["us"]):
        return (f"{name} = {_f(w['us'])} +- {_f(w['se'])} m/s ({w['steadiness']}: "
                f"{_f(w['us_early'])} +- {_f(w['se_early'])} m/s over 15-50 % of the depth, "
                f"{_f(w['us_late'])} +- {_f(w['se_late'])} over 50-85 %)")
    return f"{name}: none fitted, {w['note']}"


def report_text(s):
    """The short human-readable report of a summary dict (compression positive)."""
    b, f, p, h, r = s["bed"], s["front"], s["precursor"], s["shocked"], s["reference"]
    d, j, c, sn = s["drive"], s["jump"], s["compaction"], s["snowplow"]
    bd, m = s["bound"], s["mesh"]
    drive = (f"piston driven at {_f(d['impact_speed'])} m/s"
             + (f", brought to rest over {_f(d['ramp_down'], 1e6, '.2f')} us and released at "
                f"{_f(d['release'], 1e6, '.2f')} us" if d["release"] is not None else "")
             if d["kind"] == "piston" else f"free hammer at {_f(d['impact_speed'])} m/s")
    lines = [
        f"Shock run {s['file']}  (stresses compressive-positive)",
        f"bed: H0 = {_f(b['H0'], 1e3, '.3f')} mm (top from {b['top_from']}), width "
        f"{_f(b['width'], 1e3, '.3f')} mm, {b['n_grains']} grains of {b['grain_material']}, "
        f"mean diameter {_f(b['mean_grain_diameter'], 1e3, '.3f')} mm",
        f"rho0 = {_f(b['rho0'])} kg/m3 (experiment {_f(b['reference_density'])}), "
        f"phi0 = {_f(b['phi0'], 1, '.3f')} of rho_s = {_f(b['solid_density'])}",
        f"drive: {drive}; face speed within {_f(d['face_deviation'], 100)} % of it until the "
        "front reached the bottom",
        "compaction front (each grain's first passage of "
        f"{f['front_fraction']} x the impact speed): " + _speed_line("Us", f),
        "precursor (first motion, "
        f"{p['fraction']} x the impact speed): " + _speed_line("speed", p),
        f"  fit of {f['fit_grains']} grains' first passages against their depths "
        f"{_f(f['fit_depth_range'][0], 1e3, '.2f')}-{_f(f['fit_depth_range'][1], 1e3, '.2f')} "
        f"mm ({f['fit_missing']} never passed), rms scatter {_f(f['fit_rms'], 1e6, '.3f')} us; "
        f"front passes them {_f(f['fit_t_start'], 1e6, '.2f')}-"
        f"{_f(f['fit_t_end'], 1e6, '.2f')} us",
        f"arrival at the bottom: compaction front {_f(f['arrival_front'], 1e6, '.2f')} us "
        f"(fit {_f(f['arrival_fit'], 1e6, '.2f')} us), precursor "
        f"{_f(p['arrival'], 1e6, '.2f')} us, anvil gauge rise "
        f"{_f(f['arrival_gauge'], 1e6, '.2f')} us; report {_f(r['arrival'], 1e6, '.2f')} us",
        f"behind the front: up = {_f(h['up'])} m/s (hammer face {_f(h['hammer_speed'])} m/s), "
        f"rho1 = {_f(h['rho1'])} kg/m3; share of the bed's momentum ahead of the front "
        f"{_f(h['momentum_ahead'], 100)} %",
        f"stress behind the front: {_f(h['sigma'], 1e-6)} MPa ({h['sigma_source']}); "
        f"rho0 Us up = {_f(h['rho0_us_up'], 1e-6)} MPa; read in the bed "
        f"{_f(h['sigma_bed'], 1e-6)} MPa, hammer gauge {_f(h['sigma_gauge'], 1e-6)} MPa",
        f"jump conditions: mass {_f(j['mass_closure'], 100)} %, in strain form (up/Us against "
        f"1 - rho0/rho1) {_f(j['mass_strain_closure'], 100)} %; momentum "
        f"{_f(j['momentum_closure'], 100)} % ({h['sigma_source']}), "
        f"{_f(j['momentum_closure_bed'], 100)} % with the stress read in the bed",
        f"snowplow (rigid grains, every pore closed) at the measured up: Us = {_f(sn['us'])} "
        f"m/s (sigma {_f(sn['sigma'], 1e-6)} MPa); at the drive speed "
        f"{_f(sn['us_at_impact_speed'])} m/s",
        f"bed compacted to its grains' own compression at the measured stress: rho1 <= "
        f"{_f(bd['rho1_max'])} kg/m3, Us >= {_f(bd['us_min'])} m/s: "
        + bound_word(bd["kept"], "BROKEN (not a state of this bed)"),
        f"grain meshes: {_f(m['folded_front'], 100, '.2f')} % of the grains' area in folded "
        f"corners while the front crosses, {_f(m['folded_end'], 100, '.2f')} % at the end"
        + ("" if m["folded_max"] <= FOLDED_LIMIT else
           f" (more than {_f(FOLDED_LIMIT, 100, '.0f')} %: meshes folded over themselves, the "
           "answer is the mesh's)")
        + f"; grain nodes inside another grain's interior elements at the end "
          f"{_f(m['interpenetrated_end'], 100, '.2f')} %"
        + ("" if not m["interpenetrated_end"] > 0.0 else
           " (contacts pressed past the other grain's boundary elements; under the area law "
           "nothing opposes them there and the answer is not the bed's)"),
        _escape_line(m["escape"]),
        f"compaction strain (centre of mass): peak {_f(c['peak'], 1, '.3f')} at "
        f"{_f(c['t_peak'], 1e6, '.2f')} us, final {_f(c['final'], 1, '.3f')} at "
        f"{_f(c['t_final'], 1e6, '.2f')} us ({_f(c['kept'], 100, '.0f')} % of the peak kept); "
        f"from the bed height: peak {_f(c['peak_height'], 1, '.3f')}, final "
        f"{_f(c['final_height'], 1, '.3f')}",
        _reshock_line(s["reshock"]),
        f"peak gauge stresses: hammer {_f(s['gauges']['hammer_peak'], 1e-6)} MPa, anvil "
        f"{_f(s['gauges']['anvil_peak'], 1e-6)} MPa",
        f"elastic wave speed of the grains sqrt((K+4G/3)/rho) = {_f(s['elastic_wave_speed'])} m/s",
        f"energy balance error: last {_f(s['energy']['balance_error_last'], 100, '.2f')} %, "
        f"max {_f(s['energy']['balance_error_max'], 100, '.2f')} %",
    ]
    hs = s.get("hotspots")
    if hs:
        t = hs["shocked"]
        lines.append(f"temperature behind the front at {_f(hs['time'], 1e6, '.2f')} us "
                     f"(mass-weighted): mean {_f(t['mean'], 1, '.1f')} K, p99 "
                     f"{_f(t['p99'], 1, '.1f')} K, p99.9 {_f(t['p99.9'], 1, '.1f')} K, max "
                     f"{_f(t['max'], 1, '.1f')} K; {t['n_spots']} hot spot(s) above "
                     f"{_f(hs['spot_threshold'], 1, '.0f')} K, at most {hs['most_spots']} "
                     "(hot-spot census in -hotspots.*)")
    lines += [
        "",
        "1997 report: a steady wave with up = "
        f"{_f(r['impact_speed'])} m/s into {_f(r['density'])} kg/m3 of {_f(r['solid_density'])}"
        f" kg/m3 crystal must run at >= up/(1 - rho0/rho_s) = "
        f"{_f(r['us_min_at_impact_speed'])} m/s, so its "
        f"{_f(r['us'])} m/s front implies up <= {_f(r['up_max_at_reference_us'])} m/s.",
        f"This run (rho0/rho_s = {_f(b['phi0'], 1, '.3f')}): Us = {_f(f['us'])} m/s "
        f"with up = {_f(h['up'])} m/s, arrival {_f(f['arrival_front'], 1e6, '.2f')} us against "
        f"the report's {_f(r['arrival'], 1e6, '.2f')} us.",
    ]
    lines += [f"note: {n}" for n in s["notes"]]
    if s.get("run"):
        lines += ["", "run:"] + [f"  {k}: {_show(v)}" for k, v in s["run"].items()]
    return "\n".join(lines) + "\n"


def bound_word(kept, broken="BROKEN", none="n/a (no front)"):
    """How a bound check reads: kept, ``broken``, or ``none`` where no front was measured."""
    return none if kept is None else ("kept" if kept else broken)
