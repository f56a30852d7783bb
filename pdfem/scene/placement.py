"""The grains of a scene at t = 0 as arrays, and the placement rules: cell size and skin from
the grain sizes, everything inside the domain box, nothing overlapping (hand-placed grains) or
every node clear of the blocks (a prepared bed)."""

import math

import numpy as np

from pdfem.scene import geometry as geo
from pdfem.scene.values import SceneError, show


def grain_arrays(inline, rows, mat_ids):
    """All grains as arrays (inline first, then the file) and a grain-label function."""
    n0 = len(inline)
    arrays = {
        "center": np.array([g["center"] for g in inline], float).reshape(n0, 2),
        "axes": np.array([g["axes"] for g in inline], float).reshape(n0, 2),
        "angle": np.array([g["angle"] for g in inline], float).reshape(n0),
        "velocity": np.array([g["velocity"] for g in inline], float).reshape(n0, 2),
        "material": np.array([mat_ids[g["material"]] for g in inline], np.int64).reshape(n0),
    }
    if rows is not None:
        arrays = {k: np.concatenate([v, rows.arrays[k]]) for k, v in arrays.items()}
        for k in ("nodes", "node_v", "elem_sig", "elem_mst"):
            if k in rows.arrays:
                arrays[k] = rows.arrays[k]

    def label(i):
        """``grains[i]`` or ``grains_file: f.csv line 12 (grain i)``."""
        if i < n0:
            return f"grains[{i}]"
        return f"grains_file: {rows.label(i - n0)} (grain {i})"

    return arrays, label


def check_geometry(r, g, label):
    """Cell size and skin; everything inside the box; no overlaps at t=0."""
    dom = r["domain"]
    box = dom["box"]
    n = g["center"].shape[0]
    blocks = [b["box"] for b in r["blocks"]]
    if n == 0 and not blocks:
        raise SceneError("grains", "the scene has no grains and no blocks")
    # Skin and cell size (0 = auto)
    diam = 2.0 * float(g["axes"].max()) if n else 0.0
    if n and "nodes" in g:
        diam = max(diam, float((g["nodes"].max(axis=1) - g["nodes"].min(axis=1)).max()))
    if dom["skin"] == 0.0 and n:
        dom["skin"] = 0.1 * 2.0 * float(g["axes"].min())
    least = diam + dom["skin"]
    if dom["cell_size"] == 0.0:
        dom["cell_size"] = least if n else max(box[2] - box[0], box[3] - box[1])
    elif dom["cell_size"] < least:
        shown = f"{least:.6g}" if float(f"{least:.6g}") >= least else f"{least * 1.000001:.6g}"
        raise SceneError("domain.cell_size", f"must be >= {shown} (largest grain diameter "
                         f"{diam:.6g} + skin {dom['skin']:.6g}) (got {dom['cell_size']!r})")
    # Periodic sides: a grain meets another at one image when the box is at least three cells
    # (a grain's cell and its two neighbours) wide
    if n and dom["periodic"] == "x" and math.floor((box[2] - box[0]) / dom["cell_size"]) < 3:
        raise SceneError("domain.box", f'must be at least 3 cells wide with domain.periodic = '
                         f'"x" (width {show(box[2] - box[0])} m, cell size '
                         f'{show(dom["cell_size"])} m)')
    # Inside the domain box
    for i, bb in enumerate(blocks):
        if bb[0] < box[0] or bb[1] < box[1] or bb[2] > box[2] or bb[3] > box[3]:
            raise SceneError(f"blocks[{i}].box", "outside the domain box")
    periodic = dom["periodic"] == "x"
    if "nodes" in g:
        _bed_geometry(r, g, label, blocks, box, periodic)
        return
    lo, hi = geo.ellipse_aabb(g["center"], g["axes"], g["angle"])
    _inside_box_and_apart(*_centred_in_x(lo, hi, g["center"], periodic), box, blocks, label)
    hit = geo.first_grain_block_overlap(g["center"], g["axes"], g["angle"], blocks)
    if hit:
        raise SceneError(label(hit[0]), f"overlaps blocks[{hit[1]}] "
                         f"({r['blocks'][hit[1]]['name']}) at t=0")
    pair = _first_overlap(g, box, diam, periodic)
    if pair:
        j = label(pair[1])
        raise SceneError(label(pair[0]), f"overlaps {j.replace('grains_file: ', '')} at t=0")


def _centred_in_x(lo, hi, centre, periodic):
    """With periodic sides only a grain's centre must lie within the box in x (a grain may
    cross the seam): its box's x extent shrunk to the centre."""
    if not periodic:
        return lo, hi
    lo, hi = lo.copy(), hi.copy()
    lo[:, 0] = hi[:, 0] = centre[:, 0]
    return lo, hi


def _first_overlap(g, box, diam, periodic):
    """The first overlapping pair of hand-placed grains; with periodic sides also through the
    seam: the grains near the left side are tested once more shifted by the box's width."""
    c, axes, angle = g["center"], g["axes"], g["angle"]
    n = c.shape[0]
    if not periodic:
        return geo.first_grain_overlap(c, axes, angle)
    near = np.nonzero(c[:, 0] - box[0] < diam)[0]
    shifted = c[near] + np.array([box[2] - box[0], 0.0])
    pair = geo.first_grain_overlap(np.concatenate([c, shifted]),
                                   np.concatenate([axes, axes[near]]),
                                   np.concatenate([angle, angle[near]]))
    if pair and pair[1] >= n:
        pair = tuple(sorted((pair[0], int(near[pair[1] - n]))))
    return pair


def _inside_box_and_apart(lo, hi, box, blocks, label):
    """Grain bounding boxes (lo, hi) inside the domain box; no two blocks overlapping."""
    i = geo.first_outside(lo, hi, box)
    if i >= 0:
        raise SceneError(label(i), "outside the domain box")
    pair = geo.first_block_overlap(blocks)
    if pair:
        raise SceneError(f"blocks[{pair[0]}]", f"overlaps blocks[{pair[1]}]")


def _bed_geometry(r, g, label, blocks, box, periodic):
    """A prepared bed: every node inside the box and outside every block.

    Grains of a bed touch (their contacts carry the overlap of the contact law), so the
    ellipse overlap test of hand-placed grains does not apply, and a node may lie up to
    contact.delta_max beyond a wall or inside a block.
    """
    nodes = g["nodes"]
    tol = r["contact"]["delta_max"] if "contact" in r else 0.0
    lo, hi = nodes.min(axis=1) + tol, nodes.max(axis=1) - tol
    _inside_box_and_apart(*_centred_in_x(lo, hi, nodes.mean(axis=1), periodic), box, blocks,
                          label)
    for k, bb in enumerate(blocks):
        inside = ((nodes[:, :, 0] > bb[0] + tol) & (nodes[:, :, 0] < bb[2] - tol)
                  & (nodes[:, :, 1] > bb[1] + tol) & (nodes[:, :, 1] < bb[3] - tol)).any(axis=1)
        hit = np.nonzero(inside)[0]
        if hit.size:
            raise SceneError(label(int(hit[0])), f"overlaps blocks[{k}] "
                             f"({r['blocks'][k]['name']}) at t=0")
