"""The files of the hot-spot census: the regions' and the spots' CSV, the front-relative
CSV (shock runs), the JSON with everything, and the figures; each written atomically."""

import csv
import io
import json
import math

from pdfem.tools.analysis.hotspots import MECHANISMS, PERCENTILES
from pdfem.tools.analysis.jsontext import plain, write_atomic

FIGURES = ("-hotspots-map", "-hotspots-distribution", "-hotspots-count")
PLOT_FORMATS = ("png", "pdf", "none")


def output_files(prefix, plots="png", shock=True):
    """Paths of the files :func:`write_outputs` writes for ``prefix``; the front-relative
    CSV and figure only for a shock run."""
    out = [prefix + s for s in ("-hotspots.csv", "-hotspots-spots.csv", "-hotspots.json")]
    if shock:
        out.append(prefix + "-hotspots-front.csv")
    if plots != "none":
        out += [f"{prefix}{s}.{plots}" for s in FIGURES + (("-hotspots-front",) if shock
                                                          else ())]
    return out


def _num(v):
    """A CSV cell: numbers to 9 significant digits, NaN and None empty."""
    if v is None or (isinstance(v, float) and not math.isfinite(v)):
        return ""
    if isinstance(v, float):
        return format(v, ".9g")
    return str(v)


def _csv(header, rows):
    """CSV text of ``rows`` (lists) under ``header``."""
    buf = io.StringIO()
    w = csv.writer(buf, lineterminator="\n")
    w.writerow(header)
    for r in rows:
        w.writerow([_num(v) for v in r])
    return buf.getvalue()


def regions_csv(result):
    """One row per frame per region: distribution, area fractions, spots, front height."""
    pcts = [f"p{p:g}" for p in PERCENTILES]
    thr = result["settings"]["thresholds"]
    header = (["frame", "time", "region", "n_elements", "mass", "area", "T_mean"]
              + [f"T_{p}" for p in pcts] + ["T_max"]
              + [f"area_fraction_above_{t:g}K" for t in thr]
              + ["n_spots", "spot_area", "max_spot_diameter", "max_spot_peak", "front_y"])
    rows = []
    for fr in result["frames"]:
        for region in result["regions"]:
            d = fr[region]
            rows.append([fr["frame"], fr["time"], region, d["n_elements"], d["mass"],
                         d["area"], d["mean"]] + [d[p] for p in pcts] + [d["max"]]
                        + [d["area_fraction"][float(t)] for t in thr]
                        + [d["n_spots"], d["spot_area"], d["max_spot_diameter"],
                           d["max_spot_peak"], d.get("front_y")])
    return _csv(header, rows)


def spots_csv(result):
    """One row per spot per frame."""
    mechs = [m for m in MECHANISMS if f"heat_{m}" in result["heat_fields"]]
    header = (["frame", "time", "id", "area", "diameter", "T_peak", "T_mean", "site",
               "mechanism"] + [f"share_{m}" for m in mechs]
              + ["centroid_x", "centroid_y", "n_elements", "n_grains", "behind_front"])
    rows = [[s["frame"], s["time"], s["id"], s["area"], s["diameter"], s["peak"], s["mean"],
             s["site"], s["mechanism"]] + [s["shares"].get(m) for m in mechs]
            + [s["centroid"][0], s["centroid"][1], s["n_elements"], s["n_grains"],
               s.get("behind_front")] for s in result["spots"]]
    return _csv(header, rows)


def front_csv(result):
    """One row per bin of time since the front arrived (frames since the arrival frame)."""
    h = result["front_relative"]
    keys = ["frames", "tau", "n", "mass", "mean", "p50", "p90", "p99"]
    header = ["frames_since_arrival", "time_since_arrival", "n_elements", "mass", "T_mean",
              "T_p50", "T_p90", "T_p99"]
    return _csv(header, [[h[k][i] for k in keys] for i in range(len(h["tau"]))])


def write_outputs(result, maps, prefix, plots="png"):
    """Write every file of ``output_files(prefix, plots, shock)``; return their paths."""
    shock = result["front"] is not None
    write_atomic(prefix + "-hotspots.csv", regions_csv(result))
    write_atomic(prefix + "-hotspots-spots.csv", spots_csv(result))
    if shock:
        write_atomic(prefix + "-hotspots-front.csv", front_csv(result))
    write_atomic(prefix + "-hotspots.json", json.dumps(plain(result), indent=1) + "\n")
    if plots != "none":
        from pdfem.tools.analysis import hotplots

        hotplots.figures(result, maps, prefix, plots)
    return output_files(prefix, plots, shock)
