"""The packing of a bed: area fraction of the meshed grains, whole, interior and by depth.

Packing is the area fraction of the grains as meshed (the polygon of each grain's boundary
nodes, which its quads tile), so the bed's density is packing x the grains' density. It is
measured between the side walls (width W) and between the bed's bottom (the floor) and top:

- whole: grain area between bottom and top over W (top - bottom);
- interior: the same between bottom + d and top - d, d the mean grain diameter
  (sqrt(4 A / pi) of the meshed area A, averaged), away from the layers the floor and the
  top order;
- slices: n = round((top - bottom) / d) horizontal slices of equal thickness (about d) from
  bottom to top, each grain clipped to each slice; the interior slices are all but the first
  and the last.

Gaps: each grain's distance to its nearest neighbouring grain (boundary to boundary), and the
number of neighbours within 1 % and 5 % of d of it.
"""

import math

import numpy as np

from pdfem.kernels.cell_list import build_cells
from pdfem.kernels.polygon import nearest_gaps, slab_areas
from pdfem.mesh.ellipse import ellipse_mesh

# Neighbour distances counted by the gap figures, in mean grain diameters
NEAR = (0.01, 0.05)


def outlines(nodes, level):
    """Boundary polygons (n, 12 level, 2), counter-clockwise, of grain meshes (n, nn, 2)."""
    _, _, boundary = ellipse_mesh(1.0, 1.0, level)
    return np.ascontiguousarray(nodes[:, boundary, :])


def polygon_areas(polys):
    """Areas (n,) of polygons (n, m, 2), counter-clockwise positive (shoelace)."""
    x, y = polys[..., 0], polys[..., 1]
    return 0.5 * np.sum(x * np.roll(y, -1, axis=1) - np.roll(x, -1, axis=1) * y, axis=1)


def _fraction(polys, x0, x1, y0, y1):
    """Grain area inside the band y0 <= y <= y1 over its area W (y1 - y0)."""
    if not y1 > y0:
        return math.nan
    out = np.empty(polys.shape[0])
    slab_areas(polys, y0, y1, out)
    return float(out.sum() / ((x1 - x0) * (y1 - y0)))


def profile(polys, x0, x1, bottom, top):
    """Packing of a bed (see the module docstring): a dict of whole, interior, the slices and
    the mean grain diameter."""
    areas = polygon_areas(polys)
    d = float(np.mean(np.sqrt(4.0 * areas / np.pi)))
    nsl = max(1, int(round((top - bottom) / d)))
    edges = np.linspace(bottom, top, nsl + 1)
    slices = np.array([_fraction(polys, x0, x1, edges[k], edges[k + 1]) for k in range(nsl)])
    inner = slices[1:-1] if nsl > 2 else np.zeros(0)
    return {"whole": _fraction(polys, x0, x1, bottom, top),
            "interior": _fraction(polys, x0, x1, bottom + d, top - d),
            "slice_edges": edges, "slices": slices,
            "interior_slices_min": float(inner.min()) if inner.size else math.nan,
            "interior_slices_max": float(inner.max()) if inner.size else math.nan,
            "diameter": d, "bottom": float(bottom), "top": float(top), "width": x1 - x0,
            "grain_area": float(areas.sum()), "grains": int(polys.shape[0])}


def gaps(polys):
    """Gap figures of a bed of disjoint grains: nearest-neighbour gaps over the mean
    diameter d (min, 10th, 50th, 90th percentile) and neighbours within NEAR x d per grain."""
    n = polys.shape[0]
    cen = polys.mean(axis=1)
    verts = np.ascontiguousarray(polys - cen[:, None, :])
    rad = np.sqrt((verts ** 2).sum(axis=2)).max(axis=1)
    d = float(np.mean(np.sqrt(4.0 * polygon_areas(polys) / np.pi)))
    reach = np.array(NEAR) * d
    # Cells wide enough that every neighbour within the largest reach is in the 3 x 3 block
    h = 2.0 * float(rad.max()) + float(reach[-1])
    lo = cen.min(axis=0)
    nx, ny = (max(1, int((cen.max(axis=0)[k] - lo[k]) / h) + 1) for k in range(2))
    cell, start, items = np.empty(n, np.int64), np.zeros(nx * ny + 1, np.int64), \
        np.empty(n, np.int64)
    cx, cy = np.ascontiguousarray(cen[:, 0]), np.ascontiguousarray(cen[:, 1])
    build_cells(cx, cy, lo[0], lo[1], h, nx, ny, cell, start, items)
    gap, near = np.empty(n), np.zeros((n, len(NEAR)), np.int64)
    nearest_gaps(cx, cy, verts, rad, cell, start, items, nx, ny, reach, gap, near)
    g = gap[np.isfinite(gap)] / d
    pct = np.percentile(g, [10, 50, 90]) if g.size else [math.nan] * 3
    out = {"gap_min": float(g.min()) if g.size else math.nan, "gap_p10": float(pct[0]),
           "gap_median": float(pct[1]), "gap_p90": float(pct[2])}
    for k, f in enumerate(NEAR):
        out[f"near_{round(100 * f)}pct"] = float(near[:, k].mean())
    return out


def report(prof, target=None, gap=None):
    """Lines describing a packing profile (and its gaps), for the log."""
    d = prof["diameter"]
    lines = [f"packing: {'target ' + format(target, '.3f') + ', ' if target else ''}reached "
             f"{prof['interior']:.4f} in the interior (y {prof['bottom'] + d:.4g} to "
             f"{prof['top'] - d:.4g} m, one mean grain diameter {d:.4g} m from the bottom and "
             f"the top), {prof['whole']:.4f} over the whole bed ({prof['grains']} grains, "
             f"{prof['width']:.4g} m wide, {prof['top'] - prof['bottom']:.4g} m high)"]
    thick = prof["slice_edges"][1] - prof["slice_edges"][0]
    lines.append(f"packing by depth ({len(prof['slices'])} slices {thick:.4g} m thick, bottom "
                 "to top; [] = first and last): "
                 + " ".join(f"[{v:.3f}]" if k in (0, len(prof["slices"]) - 1) else f"{v:.3f}"
                            for k, v in enumerate(prof["slices"])))
    if math.isfinite(prof["interior_slices_min"]):
        lines.append(f"interior slices from {prof['interior_slices_min']:.3f} to "
                     f"{prof['interior_slices_max']:.3f}")
    if gap is not None:
        lines.append(f"gaps to the nearest grain / d: min {gap['gap_min']:.3g}, 10 % "
                     f"{gap['gap_p10']:.3g}, median {gap['gap_median']:.3g}, 90 % "
                     f"{gap['gap_p90']:.3g}; neighbours per grain within 0.01 d "
                     f"{gap['near_1pct']:.2f}, within 0.05 d {gap['near_5pct']:.2f}")
    return lines


def attributes(prof, target, density):
    """Bed-file attributes of a packing profile (``target`` None: not asked for)."""
    out = {"packing_fraction": prof["interior"], "packing_whole": prof["whole"],
           "packing_slices": prof["slices"], "slice_edges": prof["slice_edges"],
           "mean_diameter": prof["diameter"], "bed_bottom": prof["bottom"],
           "bed_top": prof["top"], "width": prof["width"],
           "grain_mass": density * prof["grain_area"],
           "bed_density": density * prof["whole"]}
    if target is not None:
        out["packing_target"] = target
    return out


def check(prof, target, tol, slice_tol, where):
    """None when the interior packing is within tol of target and every interior slice within
    slice_tol; otherwise the one-line reason, naming ``where``."""
    if target is None:
        return None
    got = prof["interior"]
    if not abs(got - target) <= tol:
        return (f"{where}: {target:g} not reached: the bed's interior packs at {got:.4f} "
                f"(tolerance {tol:g})")
    lo, hi = prof["interior_slices_min"], prof["interior_slices_max"]
    worst = max(abs(lo - target), abs(hi - target)) if math.isfinite(lo) else 0.0
    if not worst <= slice_tol:
        return (f"{where}: {target:g} reached in the interior ({got:.4f}) but not uniformly: "
                f"the interior slices pack from {lo:.3f} to {hi:.3f} (tolerance "
                f"{slice_tol:g})")
    return None
