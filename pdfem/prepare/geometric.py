"""Geometric preparation: grains placed at random and grown to a target packing, no overlaps.

The standard route of grain-resolved shock studies, where gravity does not act on the
microsecond scale of the run: the bed is a frozen arrangement of disjoint grains, not a
static equilibrium, and its grains need not touch.

1. Grains: semi-axes a from ``prepare.semi_axis``, b = a x ``aspect``, angles, drawn from one
   seeded generator (PCG64) until the meshed area reaches packing x W x height (the last grain
   is kept when that comes closer to the target); then every grain is scaled by the one
   factor (within half a grain's area of 1) that makes the area the target exactly.
2. Placement at a reduced size s0 (area fraction 0.3): random sequential addition, stratified
   by depth: the bed is cut into n = round(height / d) layers (d the mean grain diameter) and
   the grains, in draw order, fill one layer after the other with equal shares of the area;
   a grain's centre is drawn uniformly in its layer. Without the layers the packing would
   inherit the density fluctuations of a random placement, a few hundredths per layer of a
   bed 16 grains wide.
3. Growth (Lubachevsky-Stillinger style, with Monte Carlo moves instead of event-driven
   dynamics, and a size per grain): each cycle is one sweep of random moves (translation and
   rotation, each kept when the moved grain overlaps nothing at the current sizes), then each
   grain grows half-way to the largest size at which it overlaps nothing (exact: contact
   scales of the polygons, pdfem.kernels.packing), by 1 % at most. The step adapts to keep
   about a third of the moves. Ends when every grain is at full size; stops with an
   InputError when the packing grows by less than 1e-4 over 500 cycles (jammed: the target
   is too dense for the route; targets to 0.80 are reached for the shot-912 grains).
4. ``prepare.sweeps`` more sweeps at full size let the arrangement forget how it was grown.

The polygons are the grain meshes' boundary polygons, so the packing is the meshed grains'.
Everything runs on one rank from one seed: the bed is the same on any number of ranks.
"""

import math
import time

import numpy as np

from pdfem.errors import InputError
from pdfem.kernels.cell_list import build_cells
from pdfem.kernels.packing import (
    grow_sweep,
    mc_sweep,
    min_pair_scale,
    rotate_into,
    rsa_place,
)
from pdfem.kernels.polygon import slab_areas
from pdfem.mesh.ellipse import ellipse_mesh, place
from pdfem.prepare.packing import polygon_areas

# Area fraction of the random placement at the reduced size
PHI_START = 0.3
# Tries of random sequential addition per grain, per round, and rounds
TRIES, ROUNDS = 64, 50
# Grains placed per call of the placement kernel (bounds its random numbers)
CHUNK = 4096
# Growth cycles at most; a growth of the packing by less than STALL_GROWTH (relative) over
# STALL cycles is jammed
MAX_CYCLES, STALL, STALL_GROWTH = 200000, 500, 1e-4
# Largest relative growth of a grain per cycle
RATE = 0.01
# Accepted fraction of moves the step size aims at, and its bounds in grain radii
ACCEPT = (0.25, 0.45)
STEP_MAX, STEP_MIN = 0.25, 1e-6
# Standard deviation of a slice's packing that the penalty on the depth profile aims at
SLICE_SIGMA = 0.004


def draw_grains(rng, area, semi_axis, aspect, unit_area):
    """Semi-axes a, b and angles of grains, in draw order, whose meshed areas add up to
    ``area`` (``unit_area``: meshed area of the grain with a = b = 1)."""
    smallest = unit_area * semi_axis[0] ** 2 * aspect[0]
    nmax = int(math.ceil(area / smallest)) + 1
    a = rng.uniform(semi_axis[0], semi_axis[1], nmax)
    b = a * rng.uniform(aspect[0], aspect[1], nmax)
    angle = rng.uniform(0.0, np.pi, nmax)
    cum = np.cumsum(unit_area * a * b)
    n = int(np.searchsorted(cum, area))
    # Keep the grain that crosses the target when that comes closer
    if n < nmax and (n == 0 or cum[n] - area < area - cum[n - 1]):
        n += 1
    if n == 0:
        return a[:0], b[:0], angle[:0]
    # One common scale makes the meshed area exactly the target
    f = np.sqrt(area / cum[n - 1])
    return f * a[:n], f * b[:n], angle[:n]


def _layers(areas, bottom, top, d):
    """Per grain the y range [lo, hi] of its layer: equal area shares, in draw order."""
    nl = max(1, int(round((top - bottom) / d)))
    cum = np.cumsum(areas) - 0.5 * areas
    k = np.minimum((cum / areas.sum() * nl).astype(np.int64), nl - 1)
    edges = np.linspace(bottom, top, nl + 1)
    return edges[k], edges[k + 1]


class Packing:
    """Hard grain polygons in the box [x0, y0, x1, y1]: placement, growth, shaking."""

    def __init__(self, a, b, angle, level, box, rng):
        unit, _, bnd = ellipse_mesh(1.0, 1.0, level)
        self.base = np.ascontiguousarray(unit[bnd][None, :, :] * np.stack([a, b], 1)[:, None, :])
        self.n = a.shape[0]
        self.a, self.b = a, b
        self.angle = angle.copy()
        self.rad = a.copy()
        self.box = np.array(box, float)
        self.rng = rng
        self.cx, self.cy = np.zeros(self.n), np.zeros(self.n)
        self.verts = np.zeros_like(self.base)
        self.trial = np.zeros_like(self.base[0])
        # Cells: the largest pair reach plus the largest move of a sweep on either side
        rmin = float(self.rad.min())
        self.step_max = STEP_MAX * rmin
        self.h = 2.0 * float(self.rad.max()) + 2.0 * math.sqrt(2.0) * self.step_max
        self.nx = max(1, int((box[2] - box[0]) / self.h))
        self.ny = max(1, int((box[3] - box[1]) / self.h))
        self.h = max((box[2] - box[0]) / self.nx, (box[3] - box[1]) / self.ny)
        self.cell = np.zeros(self.n, np.int64)
        self.start = np.zeros(self.nx * self.ny + 1, np.int64)
        self.items = np.zeros(self.n, np.int64)
        self.step = 0.1 * rmin
        self.sweeps = 0
        self.scale = np.ones(self.n)

    def fraction(self):
        """Area fraction of the grains at their current scales in the box."""
        b = self.box
        return float((self.scale ** 2 * polygon_areas(self.base)).sum()) / \
            ((b[2] - b[0]) * (b[3] - b[1]))

    def place(self, s, lo, hi):
        """Random sequential addition at scale s, grain centres in [lo_i, hi_i] (y)."""
        self.scale[:] = s
        head = np.full(self.nx * self.ny, -1, np.int64)
        nxt = np.full(self.n, -1, np.int64)
        first = 0
        while first < self.n:
            last = min(first + CHUNK, self.n)
            for _ in range(ROUNDS):
                rnd = self.rng.random((last - first, TRIES, 2))
                first = rsa_place(self.cx, self.cy, self.angle, self.verts, self.base,
                                  self.rad, rnd, lo, hi, s, self.box, self.h, self.nx, self.ny,
                                  head, nxt, first, self.trial)
                if first == last:
                    break
            else:
                raise InputError(f"prepare.packing: grain {first} found no place at the "
                                 f"starting area fraction {PHI_START} after "
                                 f"{TRIES * ROUNDS} tries (grains too large for the bed?)")

    def _cells(self):
        """Sort the grains into the cell grid."""
        build_cells(self.cx, self.cy, self.box[0], self.box[1], self.h, self.nx, self.ny,
                    self.cell, self.start, self.items)

    def limit(self):
        """Common scale at which some grain would first touch another or a wall."""
        self._cells()
        return min_pair_scale(self.cx, self.cy, self.verts, self.rad, self.box, self.cell,
                              self.start, self.items, self.nx, self.ny)

    def slice_areas(self, edges):
        """Grain area in each slice between ``edges`` (at full size)."""
        polys = self.verts + np.stack([self.cx, self.cy], 1)[:, None, :]
        out, part = np.zeros(edges.shape[0] - 1), np.empty(self.n)
        for k in range(out.shape[0]):
            slab_areas(polys, edges[k], edges[k + 1], part)
            out[k] = part.sum()
        return out

    def sweep(self, edges=None, slab=None, target=0.0, beta=0.0):
        """One Monte Carlo sweep at the grains' scales, with the depth penalty when beta > 0
        (see mc_sweep); adapts the step; returns the accepted fraction."""
        self._cells()
        rnd = self.rng.random((self.n, 4))
        if edges is None:
            edges, slab = np.zeros(1), np.zeros(0)
        acc = mc_sweep(self.cx, self.cy, self.angle, self.verts, self.base, self.rad,
                       self.scale, rnd, self.step, self.box, self.cell, self.start, self.items,
                       self.nx, self.ny, self.trial, edges, slab, target, beta) / self.n
        self.sweeps += 1
        # Aim at ACCEPT: shrink the step when few moves pass, grow it when many do
        if acc < ACCEPT[0]:
            self.step = max(0.7 * self.step, STEP_MIN * float(self.rad.min()))
        elif acc > ACCEPT[1]:
            self.step = min(1.3 * self.step, self.step_max)
        return acc

    def grow(self, target_phi):
        """Grow every grain to full size (see the module docstring); InputError when the
        growth stalls (jammed)."""
        mark = self.fraction()
        for cycle in range(MAX_CYCLES):
            self.sweep()
            self._cells()
            smin = grow_sweep(self.cx, self.cy, self.verts, self.rad, self.scale, RATE,
                              self.box, self.cell, self.start, self.items, self.nx, self.ny)
            if smin >= 1.0:
                return cycle + 1
            # Stalled: the packing grew by less than STALL_GROWTH over the last STALL cycles
            if (cycle + 1) % STALL == 0:
                phi = self.fraction()
                if phi < mark * (1.0 + STALL_GROWTH):
                    break
                mark = phi
        raise InputError(f"prepare.packing: {target_phi:g} is too dense for the geometric "
                         f"route: the grains jammed at a packing of {self.fraction():.4f} on "
                         "the way")

    def nodes(self, level):
        """Node positions (n, nn, 2) of the grain meshes at the final places."""
        out = []
        for i in range(self.n):
            xy, _, _ = ellipse_mesh(float(self.a[i]), float(self.b[i]), level)
            out.append(place(xy, (self.cx[i], self.cy[i]), self.angle[i]))
        return np.array(out)


def pack(pr, box, level, log):
    """The geometric bed of ``[prepare]`` (resolved) in ``box`` = [x0, floor, x1, top]:
    (rows (n, 5) x, y, a, b, angle; nodes (n, nn, 2); figures)."""
    t0 = time.perf_counter()
    rng = np.random.default_rng(pr["seed"])
    xy, _, bnd = ellipse_mesh(1.0, 1.0, level)
    unit_area = float(polygon_areas(xy[bnd][None])[0])
    width, height = box[2] - box[0], box[3] - box[1]
    target = pr["packing"]
    a, b, angle = draw_grains(rng, target * width * height, pr["semi_axis"], pr["aspect"],
                              unit_area)
    if a.size == 0:
        raise InputError(f"prepare.height: a bed {height:g} m high holds no grain at packing "
                         f"{target:g}")
    pk = Packing(a, b, angle, level, box, rng)
    phi = pk.fraction()
    s0 = min(1.0, math.sqrt(PHI_START / phi))
    areas = unit_area * a * b
    d = float(np.mean(np.sqrt(4.0 * areas / np.pi)))
    lo, hi = _layers(areas, box[1], box[3], d)
    pk.place(s0, lo, hi)
    t1 = time.perf_counter()
    cycles = pk.grow(target)
    t2 = time.perf_counter()
    # Shaking at full size with the penalty on the depth profile
    edges = np.linspace(box[1], box[3], max(1, int(round(height / d))) + 1)
    share = target * width * (edges[1] - edges[0])
    beta = 0.5 / (SLICE_SIGMA * width * (edges[1] - edges[0])) ** 2
    slab = pk.slice_areas(edges)
    for _ in range(pr["sweeps"]):
        pk.sweep(edges, slab, share, beta)
    # Guard of the whole construction: nothing overlaps at full size
    if not pk.limit() > 1.0:
        raise RuntimeError("geometric packing: grains overlap at full size")
    t3 = time.perf_counter()
    for i in range(pk.n):
        rotate_into(pk.base[i], pk.angle[i], pk.verts[i])
    log(f"prepare: geometric: {pk.n} grains, area fraction {phi:.4f} of the box; placed at "
        f"size {s0:.3f} in {t1 - t0:.2f} s, grown to full size in {cycles} cycles "
        f"({t2 - t1:.2f} s), {pr['sweeps']} sweeps at full size ({t3 - t2:.2f} s)")
    rows = np.stack([pk.cx, pk.cy, a, b, pk.angle], axis=1)
    figs = {"grains": pk.n, "box_packing": phi, "start_scale": s0, "growth_cycles": cycles,
            "sweeps": pr["sweeps"], "place_s": t1 - t0, "grow_s": t2 - t1,
            "shake_s": t3 - t2}
    return rows, pk.nodes(level), figs
