"""Temperatures relative to the compaction front: the front of a shock run as ``analyse``
finds it, each element's arrival time, and temperature against time since arrival.

The front and "behind the front" are those of :mod:`pdfem.tools.analysis.front`: layers one mean
grain diameter thick scanned down from the hammer face, a layer shocked when its grains move
down faster than [shock].front_fraction times the face's speed; the front y_f only moves
down; a grain is behind it when its centroid lies between y_f and the hammer face.
"""

import numpy as np

from pdfem.tools.analysis import front as fr
from pdfem.tools.analysis.hotspots import weighted_percentiles

NAN = float("nan")
FRONT_PERCENTILES = (50.0, 90.0, 99.0)


def front_history(run):
    """The compaction front of a :class:`~pdfem.tools.analysis.runfile.Run` (a shock run): y_f
    (F,), the shocked-grain mask (F, ng), the impact time, the bed's initial top and bottom,
    and the front's arrival at the bottom (y_f reaching half a mean grain diameter above the
    anvil face, as ``analyse`` reports it)."""
    diam = float(np.mean(run.grain_diam))
    geo = fr.bed_geometry(run.grain_top0, run.hammer_y[0], run.anvil_y[0], diam)
    fp = fr.front_positions(run.time, run.grain_y, run.grain_vy, run.grain_mass, run.hammer_y,
                            run.hammer_vy, run.anvil_y, geo["y_top0"], diam,
                            float(run.shock["front_fraction"]))
    arrival = fr.first_below(run.time, fp["y_f"], geo["y_bottom0"] + 0.5 * diam)
    return {"y_f": fp["y_f"], "shocked": fp["shocked"], "t_impact": fp["t_impact"],
            "y_top0": geo["y_top0"], "y_bottom0": geo["y_bottom0"], "arrival_bottom": arrival,
            "front_fraction": float(run.shock["front_fraction"]), "layer": diam}


def arrival_times(time, y_f, heights):
    """First time the front y_f (F,), never rising, comes down to each of ``heights`` (n,),
    linear between frames, as :func:`pdfem.tools.analysis.front.first_below`; NaN if never."""
    t, y = np.asarray(time, float), np.asarray(y_f, float)
    h = np.asarray(heights, float)
    # -y_f is non-decreasing: the first frame at or below a height is a sorted search
    k = np.searchsorted(-y, -h, side="left")
    out = np.full(h.shape, NAN)
    ok = k < len(t)
    first = ok & (k == 0)
    out[first] = t[0]
    mid = ok & (k > 0)
    k1 = k[mid]
    y0, y1 = y[k1 - 1], y[k1]
    out[mid] = t[k1 - 1] + (y0 - h[mid]) / (y0 - y1) * (t[k1] - t[k1 - 1])
    return out


class FrontRelative:
    """Temperature of the elements the front crosses against time since it arrived.

    Binned on the frame times: an element's arrival frame is the first frame at or after
    its arrival time t_a, and frame k falls in bin j = k - (arrival frame), so every element
    gives exactly one sample to each bin it reaches (j < 0: before the front arrived). A
    bin's time since arrival is the mean of its samples' t_k - t_a; with frames dt apart it
    lies in [j dt, (j + 1) dt). Per bin: the elements' count, and their mass-weighted mean
    and percentiles (:func:`pdfem.tools.analysis.hotspots.weighted_percentiles`).
    """

    def __init__(self, time, arrival, elems, mass):
        self.time = np.asarray(time, float)
        dt = np.diff(self.time)
        self.dt = float(np.median(dt)) if dt.size else NAN
        crossed = np.isfinite(arrival[elems])
        self.elems, self.arrival = elems[crossed], arrival[elems][crossed]
        self.first = np.searchsorted(self.time, self.arrival, side="left")
        self.mass = mass[self.elems]
        self.bins, self.taus, self.temps = [], [], []

    def add(self, k, temp):
        """Samples of frame ``k`` with element temperatures ``temp`` (NE,)."""
        if not self.elems.size:
            return
        self.bins.append(k - self.first)
        self.taus.append(self.time[k] - self.arrival)
        self.temps.append(temp[self.elems])

    def result(self):
        """{"frames": bin offsets j (J,), "tau": mean time since arrival (J,) [s], "n",
        "mass", "mean", "p50", "p90", "p99"} as lists, with "dt" (the median frame interval)
        and "n_elements" (the elements crossed); empty lists when none was."""
        keys = ("frames", "tau", "n", "mass", "mean") + tuple(f"p{p:g}"
                                                              for p in FRONT_PERCENTILES)
        out = {k: [] for k in keys}
        out["dt"] = self.dt
        out["n_elements"] = int(self.elems.size)
        if not self.bins:
            return out
        b, tau, tt = (np.concatenate(a) for a in (self.bins, self.taus, self.temps))
        mm = np.tile(self.mass, len(self.bins))
        order = np.argsort(b, kind="stable")
        b, tau, tt, mm = b[order], tau[order], tt[order], mm[order]
        starts = np.flatnonzero(np.r_[True, b[1:] != b[:-1]])
        for s, e in zip(starts, np.r_[starts[1:], b.size], strict=True):
            t, m = tt[s:e], mm[s:e]
            out["frames"].append(int(b[s]))
            out["tau"].append(float(tau[s:e].mean()))
            out["n"].append(int(e - s))
            out["mass"].append(float(m.sum()))
            out["mean"].append(float(t @ m / m.sum()))
            for p, v in zip(FRONT_PERCENTILES, weighted_percentiles(t, m, FRONT_PERCENTILES),
                            strict=True):
                out[f"p{p:g}"].append(float(v))
        return out
