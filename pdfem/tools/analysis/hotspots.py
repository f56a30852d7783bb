"""The hot-spot census of one frame, from plain arrays.

Definitions (temperatures in K, SI otherwise):

- An element's mass is its density times its frame-0 area (conserved); its area is the
  current one, in the frame's geometry.
- Mass-weighted percentile: sort the elements by temperature T_1 <= ... <= T_n, with masses
  m_i and total M. The p-th percentile is the smallest T_k whose cumulative mass
  m_1 + ... + m_k is at least p M: the inverse of the mass-weighted distribution function
  (numpy's ``inverted_cdf`` method with weights). The 0th is the smallest T, the 100th the
  largest.
- The area fraction above a threshold: the current area of the region's elements hotter than
  the threshold over the region's current area.
- A hot spot: a connected set of grain elements hotter than the spot threshold. Two hot
  elements connect when they share a node (within a grain) or when they are boundary
  elements of different grains whose boundary edges come within the contact tolerance of
  each other in the frame's geometry (across a contact).
- A spot's site, the first that applies: ``contact`` (one of its boundary elements touches
  another body, a grain or a block, within the contact tolerance), ``corner`` (one of its
  elements holds a grain corner: see :func:`pdfem.tools.analysis.hotgeom.corner_elements`),
  ``surface`` (it holds a free boundary element), ``interior``.
- A spot's mechanism: with the per-element cumulative heat of each mechanism (J/m, frame
  fields ``heat_<mechanism>``), the one with the largest sum over the spot's elements; its
  share is that sum over the sum of all mechanisms' (the spot's net heat), NaN when that is
  not positive. ``unknown`` without those fields.
"""

import numpy as np

from pdfem.effects.heat import MECHANISMS
from pdfem.tools.analysis.hotgeom import components, near_segments

NAN = float("nan")
PERCENTILES = (50.0, 90.0, 99.0, 99.9)
# The mechanisms of the run's heat_<mechanism> frame fields: pdfem.effects.heat.MECHANISMS
SITES = ("contact", "corner", "surface", "interior")


def weighted_percentiles(values, weights, ps):
    """Mass-weighted percentiles (len(ps),) of ``values``, as the module defines them; NaN
    for an empty set or one without mass."""
    v, w = np.asarray(values, float), np.asarray(weights, float)
    out = np.full(len(ps), NAN)
    total = w.sum()
    if v.size == 0 or not total > 0:
        return out
    order = np.argsort(v, kind="stable")
    v, cum = v[order], np.cumsum(w[order])
    for i, p in enumerate(ps):
        k = np.searchsorted(cum, p / 100.0 * total, side="left")
        out[i] = v[min(k, v.size - 1)] if p > 0 else v[np.argmax(w[order] > 0)]
    return out


def distribution(temp, mass, area, thresholds, ps=PERCENTILES):
    """Temperature distribution of a set of elements: mass-weighted mean, percentiles
    ``ps`` and max, its mass and area, and the area fraction above each threshold."""
    m, a = mass.sum(), area.sum()
    pct = weighted_percentiles(temp, mass, ps)
    out = {"n_elements": int(temp.size), "mass": float(m), "area": float(a),
           "mean": float(temp @ mass / m) if m > 0 else NAN,
           "max": float(temp.max()) if temp.size else NAN}
    out.update({f"p{p:g}": float(v) for p, v in zip(ps, pct, strict=True)})
    out["area_fraction"] = {float(t): float(area[temp > t].sum() / a) if a > 0 else NAN
                            for t in thresholds}
    return out


class Topology:
    """What the census needs of the mesh, fixed over the run: grain elements, their
    neighbours through shared nodes, boundary edges and corner elements."""

    def __init__(self, conn, elem_body, grain, pairs, bedges, bowner, corner, tol):
        self.conn, self.elem_body = conn, elem_body
        self.grain = grain            # (NE,) bool, grain elements
        self.pairs = pairs            # (P, 2) grain elements sharing a node
        self.bedges = bedges          # (B, 2) boundary edges of every body
        self.bowner = bowner          # (B,) their elements
        self.boundary = np.zeros(len(conn), bool)
        self.boundary[bowner] = True
        self.corner = corner          # (NE,) bool
        self.tol = tol                # contact tolerance [m]


def contacts(topo, x, elems):
    """For the elements ``elems`` (indices) in the geometry ``x``: (touching (NE,) bool, the
    element touches another body; links (L, 2), element pairs of different grains touching,
    both in ``elems``)."""
    ne = len(topo.conn)
    sel = np.zeros(ne, bool)
    sel[elems] = True
    q = np.flatnonzero(sel[topo.bowner])
    qi, ej = near_segments(x, topo.bedges[q], topo.bedges, topo.tol)
    a, b = topo.bowner[q[qi]], topo.bowner[ej]
    other = topo.elem_body[a] != topo.elem_body[b]
    touching = np.zeros(ne, bool)
    touching[a[other]] = True
    link = other & sel[b] & topo.grain[b]
    return touching, np.unique(np.sort(np.stack([a[link], b[link]], axis=1), axis=1), axis=0)


def _mechanism(heat, idx):
    """(name, {mechanism: share}) of the spot's elements ``idx`` from the heat fields."""
    if not heat:
        return "unknown", {}
    sums = {m: float(heat[m][idx].sum()) for m in MECHANISMS if m in heat}
    total = sum(sums.values())
    name = max(sums, key=lambda m: sums[m])
    return name, {m: s / total if total > 0 else NAN for m, s in sums.items()}


def _site(touching, corner, boundary):
    """The site of a spot from its elements' flags (first that applies)."""
    if touching.any():
        return "contact"
    if corner.any():
        return "corner"
    if boundary.any():
        return "surface"
    return "interior"


def find_spots(topo, x, temp, mass, area, threshold, heat=None):
    """The hot spots of one frame: grain elements hotter than ``threshold`` connected as the
    module says. ``temp``, ``mass``, ``area``: (NE,); ``heat``: {mechanism: (NE,)} or None.

    Returns (spots, label (NE,)): spots as dicts sorted by decreasing area (id 1 the largest)
    with area, diameter sqrt(4A/pi), peak and mass-weighted mean T, the area-weighted
    centroid of the element centroids, element and grain counts, site, mechanism and shares,
    and ``elements`` (the element indices); label is the spot id of each element, 0 outside.
    """
    hot = np.flatnonzero(topo.grain & (temp > threshold))
    label = np.zeros(len(temp), np.int64)
    if hot.size == 0:
        return [], label
    touching, links = contacts(topo, x, hot)
    inside = np.zeros(len(temp), bool)
    inside[hot] = True
    within = topo.pairs[inside[topo.pairs[:, 0]] & inside[topo.pairs[:, 1]]]
    # Components over the hot elements, renumbered 0..n-1
    local = np.full(len(temp), -1)
    local[hot] = np.arange(hot.size)
    comp = components(hot.size, local[np.concatenate([within, links])])
    roots, which = np.unique(comp, return_inverse=True)
    centroid = x[topo.conn].mean(axis=1)
    spots = []
    for r in range(roots.size):
        idx = hot[which == r]
        a, m = area[idx].sum(), mass[idx].sum()
        mech, shares = _mechanism(heat, idx)
        spots.append({
            "area": float(a), "diameter": float(np.sqrt(4.0 * a / np.pi)),
            "peak": float(temp[idx].max()), "mean": float(temp[idx] @ mass[idx] / m),
            "centroid": (area[idx] @ centroid[idx] / a).tolist(),
            "n_elements": int(idx.size), "n_grains": int(np.unique(topo.elem_body[idx]).size),
            "site": _site(touching[idx], topo.corner[idx], topo.boundary[idx]),
            "mechanism": mech, "shares": shares, "elements": idx})
    spots.sort(key=lambda s: (-s["area"], s["elements"][0]))
    for i, s in enumerate(spots, start=1):
        s["id"] = i
        label[s["elements"]] = i
    return spots, label
