"""The quantities that matter in a shock run, as the accuracy study measures them.

Us and the arrival come from the front fit of the shock analysis
(:func:`pdfem.analysis.analyse`: the fitted front line reaching the bed bottom); the peak
stress is the hammer's until that arrival (the impact peak that drives the wave; later the
reflected wave loads the hammer again and both gauges keep rising as the bed locks up, so a
maximum over the whole run would measure the end time): the bed's push on a driven hammer
(contact force over the width; a rigid piston has no stress of its own), the hammer gauge's
stress on a free one; the packing fraction is the grains' area over the bed's volume at the
last frame.
"""

import math

import numpy as np

# (key, table heading, words, unit and scale for printing): the quantities that matter in a
# shock run; the CSV holds them in SI units under their keys
QUANTITIES = (
    ("us", "Us", "front speed Us", "m/s", 1.0),
    ("arrival", "arrival", "arrival of the front at the bottom", "us", 1e6),
    ("hammer_peak", "peak stress", "peak hammer gauge stress", "MPa", 1e-6),
    ("packing", "packing", "final packing fraction", "", 1.0),
)


def final_packing(run):
    """Grain area over the bed's volume (width x hammer face to anvil face) at the last frame
    of a shock run (a :class:`~pdfem.analysis.runfile.Run`)."""
    from pdfem.analysis.runfile import element_areas

    last = len(run.time) - 1
    x, _, _ = run.frame(last)
    area = element_areas(x, run.conn)[run.elem_body < run.ng].sum()
    return float(area / (run.width * (run.hammer_y[last] - run.anvil_y[last])))


def impact_peak(run, until):
    """Peak compressive stress on the hammer while the front crosses the bed (samples up to
    time ``until``; the whole run when ``until`` is NaN): the contact force over the width on
    a driven hammer, the gauge's -sigma_yy on a free one."""
    t = run.gauge_time
    g = run.gauges[run.shock["hammer_gauge"]]
    driven = run.drive["driven"] and g.get("force") is not None
    comp = g["force"][:, 1] / run.width if driven else -g["stress"][:, 1]
    sel = t <= until if math.isfinite(until) else np.ones(t.shape, bool)
    return float(comp[sel].max()) if sel.any() else math.nan


def measure(run_path, prefix):
    """The :data:`QUANTITIES` of a finished shock run (NaN where the analysis finds none);
    writes ``<prefix>-summary.json`` and ``.txt`` beside it."""
    from pdfem.analysis import analyse
    from pdfem.analysis.runfile import read_run

    s = analyse(run_path, prefix)
    run = read_run(run_path)
    arrival = s["front"]["arrival_fit"]
    arrival = math.nan if arrival is None else float(arrival)
    vals = {"us": s["front"]["us"], "arrival": arrival,
            "hammer_peak": impact_peak(run, arrival), "packing": final_packing(run)}
    return {k: math.nan if v is None else float(v) for k, v in vals.items()}
