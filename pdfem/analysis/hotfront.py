"""Temperatures relative to the compaction front: the front of a shock run as ``analyse``
finds it, each element's arrival time, and temperature against time since arrival.

The front and "behind the front" are those of :mod:`pdfem.analysis.front`: layers one mean
grain diameter thick scanned down from the hammer face, a layer shocked when its grains move
down faster than [shock].front_fraction times the face's speed; the front y_f only moves
down; a grain is behind it when its centroid lies between y_f and the hammer face.
"""

import numpy as np

from pdfem.analysis import front as fr
from pdfem.analysis.hotspots import weighted_percentiles

NAN = float("nan")
FRONT_PERCENTILES = (50.0, 90.0, 99.0)


def front_history(run):
    """The compaction front of a :class:`~pdfem.analysis.runfile.Run` (a shock run): y_f
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
    linear between frames, as :func:`pdfem.analysis.front.first_below`; NaN if never."""
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

    Each frame k gives every element with an arrival time t_a the sample (t_k - t_a, T).
    Samples are binned on the frame interval dt (the median spacing of the frame times):
    bin j holds time since arrival in [j dt, (j + 1) dt), so an element gives one sample per
    bin; before arrival j is negative. Per bin: the elements' count, and their mass-weighted
    mean and percentiles (:func:`pdfem.analysis.hotspots.weighted_percentiles`).
    """

    def __init__(self, time, arrival, elems, mass):
        dt = np.diff(time)
        self.dt = float(np.median(dt)) if dt.size and np.median(dt) > 0 else NAN
        crossed = np.isfinite(arrival[elems])
        self.elems, self.arrival = elems[crossed], arrival[elems][crossed]
        self.mass = mass[self.elems]
        self.bins, self.temps, self.masses = [], [], []

    def add(self, t, temp):
        """Samples of the frame at time ``t`` with element temperatures ``temp`` (NE,)."""
        if not (self.elems.size and np.isfinite(self.dt)):
            return
        tau = t - self.arrival
        # A small tolerance keeps a sample on the bin edge it was meant for
        self.bins.append(np.floor(tau / self.dt + 1e-9).astype(np.int64))
        self.temps.append(temp[self.elems])
        self.masses.append(self.mass)

    def result(self):
        """{"tau": bin starts (J,) [s], "dt", "n", "mass", "mean", "p50", "p90", "p99"} as
        lists; empty when the front crossed no element."""
        keys = ("tau", "n", "mass", "mean") + tuple(f"p{p:g}" for p in FRONT_PERCENTILES)
        out = {k: [] for k in keys}
        out["dt"] = self.dt
        out["n_elements"] = int(self.elems.size)
        if not self.bins:
            return out
        b, tt, mm = (np.concatenate(a) for a in (self.bins, self.temps, self.masses))
        order = np.argsort(b, kind="stable")
        b, tt, mm = b[order], tt[order], mm[order]
        starts = np.flatnonzero(np.r_[True, b[1:] != b[:-1]])
        for s, e in zip(starts, np.r_[starts[1:], b.size], strict=True):
            t, m = tt[s:e], mm[s:e]
            out["tau"].append(float(b[s] * self.dt))
            out["n"].append(int(e - s))
            out["mass"].append(float(m.sum()))
            out["mean"].append(float(t @ m / m.sum()))
            for p, v in zip(FRONT_PERCENTILES, weighted_percentiles(t, m, FRONT_PERCENTILES),
                            strict=True):
                out[f"p{p:g}"].append(float(v))
        return out
