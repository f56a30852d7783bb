"""Grain material that has left the bed: below the anvil's face or above the hammer's.

A grain node in contact overlaps the anvil or the hammer by about the contact's delta_max (the
law's pole) at most. A grain node found farther than that beyond the anvil's face (the mean
height of its face nodes) or the hammer's has gone past it: through the block, or down the
seam between the block and a side wall. The bed then holds less grain than it was given; the
share of the grains' mass in elements reaching that far bounds how much. How far grain nodes
got past the box's sides is given beside it: a contact wall lets a corner node in deeper than
the mean overlap delta its law acts on (with periodic sides there are none to pass).
"""

import numpy as np


def escape_depths(grain_bottom, grain_top, grain_xrange, anvil_y, hammer_y, box, periodic=False):
    """The farthest [m] any grain node got beyond the anvil's face (below it), the hammer's
    face (above it) and the box's left or right side (outside it), over the frames: a dict
    with keys below_anvil, above_hammer and past_sides (negative: never beyond), and the time
    index of each. Per-frame inputs: the lowest and highest grain node (nf,), the grain nodes'
    x range (nf, 2), the anvil's and the hammer's face heights (nf,); box [x0, y0, x1, y1].
    With periodic sides past_sides is None (a grain crossing a side comes back through the
    other)."""
    depth = {"below_anvil": anvil_y - grain_bottom, "above_hammer": grain_top - hammer_y,
             "past_sides": np.maximum(box[0] - grain_xrange[:, 0], grain_xrange[:, 1] - box[2])}
    if periodic:
        del depth["past_sides"]
    out = {"past_sides": None, "past_sides_frame": None}
    for key, d in depth.items():
        k = int(np.argmax(d))
        out[key], out[key + "_frame"] = float(d[k]), k
    return out


def contact_reach(scene):
    """The largest delta_max of a scene's [contact] table and its pairs [m] (0 without)."""
    c = scene.get("contact")
    if not c:
        return 0.0
    return max([float(c["delta_max"])] + [float(p["delta_max"]) for p in
                                          c.get("pairs", {}).values() if "delta_max" in p])


def escaped_mass(y, gconn, gmass, below, above):
    """Share of the grain mass gmass (NE,) in the grain elements gconn (NE, 4) with a node whose
    height y (NN,) is under ``below`` or over ``above`` [m]: an upper bound on the grain mass
    that has gone past the anvil's face (below) or the hammer's (above)."""
    out = (y < below) | (y > above)
    return float(gmass[out[gconn].any(axis=1)].sum() / gmass.sum())
