"""The hot-spot census of a thermal run, frame by frame (definitions in
:mod:`pdfem.tools.analysis.hotspots`).

Regions: ``whole``, every grain element (the hammer and anvil blocks left out), and, for a
shock run (a scene with a [shock] table), ``shocked``, the elements of the grains behind the
compaction front (:mod:`pdfem.tools.analysis.hotfront`). Hot spots are found over the whole bed; a
spot counts in the shocked region when more than half its area lies in grains behind the
front.
"""

import math

import numpy as np

from pdfem.errors import InputError
from pdfem.tools.analysis import hotgeom as hg
from pdfem.tools.analysis.hotfront import FrontRelative, arrival_times, front_history
from pdfem.tools.analysis.hotrun import read_thermal_run
from pdfem.tools.analysis.hotspots import Topology, distribution, find_spots
from pdfem.tools.analysis.runfile import element_areas, read_run

DEFAULT_THRESHOLDS = (400.0, 500.0, 600.0)
# Contact tolerance in element sizes; turning angle of a corner node [degrees]
DEFAULT_CONTACT_TOL = 0.1
DEFAULT_CORNER_ANGLE = 40.0
MAP_FRAMES = 4
NAN = float("nan")


def topology(run, contact_tol, corner_angle):
    """The :class:`~pdfem.tools.analysis.hotspots.Topology` of a
    :class:`~pdfem.tools.analysis.hotrun.ThermalRun`: the contact tolerance is ``contact_tol``
    times the element size (the median square root of the grain elements' frame-0 areas),
    corners are read in the frame-0 geometry."""
    grain = run.grain
    gel = np.flatnonzero(grain)
    h = float(np.median(np.sqrt(np.abs(element_areas(run.x0, run.conn[gel])))))
    bedges, bowner = hg.boundary_edges(run.conn)
    ing = grain[bowner]
    corner = hg.corner_elements(run.x0, bedges[ing], bowner[ing], len(run.conn),
                                math.radians(corner_angle))
    return Topology(run.conn, run.elem_body, grain, hg.node_pairs(run.conn, gel), bedges,
                    bowner, corner, contact_tol * h), h


def _map_frames(time, t_start):
    """Indices of the frames the temperature maps show: MAP_FRAMES from ``t_start`` (the
    impact, or the first frame) to the last."""
    k0 = int(np.searchsorted(time, t_start)) if np.isfinite(t_start) else 0
    k0 = min(k0, len(time) - 1)
    return sorted({int(k) for k in np.linspace(k0, len(time) - 1, MAP_FRAMES).round()})


def _spot_rows(spots, k, t, behind, area):
    """The spots of frame k as plain rows; ``behind`` (NE,) bool or None."""
    rows = []
    for s in spots:
        idx = s.pop("elements")
        if behind is not None:
            s["behind_front"] = bool(area[idx][behind[idx]].sum() > 0.5 * s["area"])
        rows.append({"frame": k, "time": t, **s})
    return rows


def _region(spots, key=None):
    """Spot count, summed area, largest diameter and hottest peak of ``spots`` (those with
    ``key`` true when given); NaN for the last two without spots."""
    sel = [s for s in spots if key is None or s.get(key)]
    return {"n_spots": len(sel), "spot_area": float(sum(s["area"] for s in sel)),
            "max_spot_diameter": max((s["diameter"] for s in sel), default=NAN),
            "max_spot_peak": max((s["peak"] for s in sel), default=NAN)}


def census(path, thresholds=DEFAULT_THRESHOLDS, spot_threshold=None,
           contact_tol=DEFAULT_CONTACT_TOL, corner_angle=DEFAULT_CORNER_ANGLE):
    """The census of the run file at ``path``: (result, maps).

    ``result`` (JSON-ready but for NaN): settings, the front (shock runs), per frame the
    regions' distributions and spot counts, every spot, and the front-relative history.
    ``maps``: the mesh (``conn``, ``grain`` mask), the domain ``box`` and, as ``frames``,
    (k, t, x, T, spot label) of the frames the temperature maps show.
    InputError (one line) for a file that cannot be read, or one without temperatures.
    """
    thresholds = tuple(sorted(float(t) for t in thresholds))
    if spot_threshold is None:
        spot_threshold = thresholds[len(thresholds) // 2]
    run = read_thermal_run(path)
    if "shock" in run.scene and not isinstance(run.scene["shock"], dict):
        raise InputError(f"{path}: [shock] in the run's scene is not a table")
    front = front_history(read_run(path)) if "shock" in run.scene else None
    topo, h = topology(run, contact_tol, corner_angle)
    grain, mass = run.grain, run.elem_mass
    gel = np.flatnonzero(grain)
    ng = int(np.sum(run.body_kind == 0))
    history = None
    if front is not None:
        # Arrival at each grain element's initial centroid height
        y0 = run.x0[run.conn, 1].mean(axis=1)
        arrival = np.full(len(mass), np.nan)
        arrival[gel] = arrival_times(run.time, front["y_f"], y0[gel])
        history = FrontRelative(run.time, arrival, gel, mass)
    show = _map_frames(run.time, front["t_impact"] if front else np.nan)
    frames, spots, maps = [], [], []
    for k, t, x, temp, heat in run.frames():
        area = np.abs(element_areas(x, run.conn))
        found, label = find_spots(topo, x, temp, mass, area, spot_threshold, heat or None)
        row = {"frame": k, "time": t,
               "whole": {**distribution(temp[gel], mass[gel], area[gel], thresholds),
                         **_region(found)}}
        behind = None
        if front is not None:
            behind = grain & front["shocked"][k][np.minimum(run.elem_body, ng - 1)]
            sel = np.flatnonzero(behind)
            row["shocked"] = {**distribution(temp[sel], mass[sel], area[sel], thresholds),
                              "front_y": float(front["y_f"][k])}
            history.add(k, temp)
        rows = _spot_rows(found, k, t, behind, area)
        if front is not None:
            row["shocked"].update(_region(rows, "behind_front"))
        spots += rows
        frames.append(row)
        if k in show:
            maps.append((k, t, x, temp, label))
    result = {
        "file": path,
        "settings": {"thresholds": list(thresholds), "spot_threshold": spot_threshold,
                     "contact_tolerance": contact_tol, "element_size": h,
                     "contact_distance": topo.tol, "corner_angle_deg": corner_angle},
        "temperature_field": run.temperature,
        "heat_fields": [f"heat_{m}" for m in run.heat],
        "n_grain_elements": int(gel.size), "n_frames": len(frames),
        "regions": ["whole", "shocked"] if front is not None else ["whole"],
        "front": None if front is None else {
            "t_impact": front["t_impact"], "arrival_bottom": front["arrival_bottom"],
            "y_top0": front["y_top0"], "y_bottom0": front["y_bottom0"],
            "front_fraction": front["front_fraction"], "layer": front["layer"],
            "y_f": front["y_f"].tolist()},
        "frames": frames, "spots": spots,
        "front_relative": history.result() if history is not None else None,
        "notes": [] if front is not None else [
            "no [shock] table in the run's scene: whole bed only, no front-relative history"],
    }
    if not run.heat:
        result["notes"].append("no heat_<mechanism> frame fields: every spot's mechanism is "
                               "unknown")
    box = run.scene.get("domain", {}).get("box") if isinstance(run.scene.get("domain"),
                                                                dict) else None
    if not (isinstance(box, list) and len(box) == 4
            and all(isinstance(v, (int, float)) and math.isfinite(v) for v in box)
            and box[2] > box[0] and box[3] > box[1]):
        box = None
    return result, {"conn": run.conn, "grain": grain, "frames": maps, "box": box}
