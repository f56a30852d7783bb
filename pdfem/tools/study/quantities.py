"""The quantities that matter in a shock run, as the accuracy study measures them.

Us and the arrival come from the front fit of the shock analysis
(:func:`pdfem.tools.analysis.analyse`: the fitted front line reaching the bed bottom); the peak
stress is what drives the wave: on a driven hammer (a piston) the bed's push on it, its contact
force over the width, averaged over the front's fit window (the momentum the wave takes; the
peak of that force is the impact of single grains on a rigid face); on a free hammer its
gauge's peak until the arrival (later the reflected wave loads the hammer again and both gauges
keep rising as the bed locks up, so a maximum over the whole run would measure the end time).
The packing fraction is the grains' area over the bed's volume at the last frame.
"""

import math

import numpy as np

# (key, table heading, words, unit and scale for printing): the quantities that matter in a
# shock run; the CSV holds them in SI units under their keys
QUANTITIES = (
    ("us", "Us", "front speed Us", "m/s", 1.0),
    ("arrival", "arrival", "arrival of the front at the bottom", "us", 1e6),
    ("hammer_stress", "hammer stress", "stress on the hammer face", "MPa", 1e-6),
    ("packing", "packing", "final packing fraction", "", 1.0),
)
# The statistical error of a quantity, where the analysis gives one: its row key
SE_KEYS = {"us": "us_se"}
# Everything a run's row holds from the analysis: the quantities and their errors
MEASURED = tuple(k for k, *_ in QUANTITIES) + tuple(SE_KEYS.values())


def final_packing(run):
    """Grain area over the bed's volume (width x hammer face to anvil face) at the last frame
    of a shock run (a :class:`~pdfem.tools.analysis.runfile.Run`)."""
    from pdfem.tools.analysis.runfile import element_areas

    last = len(run.time) - 1
    x, _, _ = run.frame(last)
    area = element_areas(x, run.conn)[run.elem_body < run.ng].sum()
    return float(area / (run.width * (run.hammer_y[last] - run.anvil_y[last])))


def impact_peak(run, until):
    """Peak compressive stress -sigma_yy of the hammer gauge while the front crosses the bed
    (samples up to time ``until``; the whole run when ``until`` is NaN)."""
    t = run.gauge_time
    comp = -run.gauges[run.shock["hammer_gauge"]]["stress"][:, 1]
    sel = t <= until if math.isfinite(until) else np.ones(t.shape, bool)
    return float(comp[sel].max()) if sel.any() else math.nan


def measure(run_path, prefix):
    """The :data:`MEASURED` values of a finished shock run (NaN where the analysis finds none):
    the :data:`QUANTITIES` and the front speed's standard error; writes
    ``<prefix>-summary.json`` and ``.txt`` beside it."""
    from pdfem.tools.analysis import analyse
    from pdfem.tools.analysis.runfile import read_run

    s = analyse(run_path, prefix)
    run = read_run(run_path)
    arrival = s["front"]["arrival_fit"]
    arrival = math.nan if arrival is None else float(arrival)
    driven = s["shocked"]["sigma_source"] == "piston force"
    stress = s["shocked"]["sigma"] if driven else impact_peak(run, arrival)
    vals = {"us": s["front"]["us"], "arrival": arrival, "hammer_stress": stress,
            "packing": final_packing(run), "us_se": s["front"]["se"]}
    return {k: math.nan if v is None else float(v) for k, v in vals.items()}
