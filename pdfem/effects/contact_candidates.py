"""Contact detection: the candidate element pairs of a rank, in contact-key order.

Detection has two levels, both at every rebuild. The cell grid gives candidate grain pairs:
grains in the same or neighbouring cells (within the cell reach) whose bounding boxes,
inflated by the skin, overlap. Their boundary-element pairs whose boxes are within the skin,
and the owned grains' boundary elements within the skin of a domain wall, are the step's
candidates, sorted once by contact key. No pair can come into contact before the next
rebuild, since rebuilds happen whenever a node may have moved half the skin. Blocks (global
bodies) are checked against every owned grain at the same rebuilds, their nodes counted in
that test like the grains': their element pairs and wall elements within the skin are merged
into the list in key order.

With periodic sides each candidate carries a third column, the period shift k of its second
element (met k box widths to the right). Grains are never moved back into the box (a grain's
cell is that of its image in the box), so k also counts the periods one grain has drifted
farther than the other; two grains meet at each image whose box is within the skin (both,
when they span the box between them), an element pair at one only.
"""

import math

import numpy as np

from pdfem.kernels.broad_phase import candidate_pairs, element_bboxes, wall_crossings
from pdfem.kernels.centroids import body_centroids
from pdfem.kernels.contact_keys import merge_candidates
from pdfem.kernels.neighbours import body_boxes, grain_pairs, key_spans, pack_keys

# Element candidates are kept at a rebuild when their boxes are within the skin: a node moves
# at most half the skin between rebuilds, so boxes that overlap now were within the skin then
# (this relative slack covers the rounding of that displacement test)
REACH_SLACK = 1e-6


def block_elements(s, g0):
    """Number of elements of the g0 global bodies (blocks), stored first."""
    return int(s.estart[g0 - 1] + s.ne[g0 - 1]) if g0 else 0


def sorted_candidates(s, pairs, welems, wids):
    """Candidates of the contact pass (pdfem.kernels.contact_pass): element pairs (a, b, k) and
    element-wall pairs (e, -1 - wall, 0), sorted by global contact key."""
    walls = np.stack([welems, -1 - wids, np.zeros_like(welems)], axis=1)
    cand = np.concatenate([pairs, walls]).astype(np.int64)
    a, b = cand[:, 0], cand[:, 1]
    pair = b >= 0
    bb = np.where(pair, b, 0)
    keys = np.stack([s.elem_gid[a], s.elem_loc[a], np.where(pair, s.elem_gid[bb], b),
                     np.where(pair, s.elem_loc[bb], 0)], axis=1)
    return cand[lexorder(keys)]


def repeated_pairs(cand):
    """Number of key-sorted candidates whose element pair is the previous one's (met at two
    period shifts: an element as wide as half the box)."""
    a, b = cand[:, 0], cand[:, 1]
    same = (a[1:] == a[:-1]) & (b[1:] == b[:-1])
    return int(np.count_nonzero(same))


def lexorder(keys):
    """Indices sorting (n, 4) int64 keys lexicographically (stable).

    When the spans of the four columns multiply to less than 2^63 the rows are packed into
    one int64 in mixed radix (an order-preserving map) and sorted once, about 15x faster
    than np.lexsort; otherwise np.lexsort. Both give the same permutation.
    """
    if keys.shape[0] < 2:
        return np.arange(keys.shape[0])
    lo, span = np.empty(4, np.int64), np.empty(4, np.int64)
    key_spans(keys, lo, span)
    # Mixed-radix packing, exact while the product of the spans fits in int64
    if math.prod(int(s) for s in span) < 2**63:
        packed = np.empty(keys.shape[0], np.int64)
        pack_keys(keys, lo, span, packed)
        return np.argsort(packed, kind="stable")
    return np.lexsort((keys[:, 3], keys[:, 2], keys[:, 1], keys[:, 0]))


class Candidates:
    """The candidates of one rank, the blocks' among them: built at each rebuild
    (:meth:`rebuild`), the same every step until the next (:meth:`step`); walls given by
    their points and inward normals; with deep, element pairs reach past the boundary
    elements (:func:`candidate_pairs`)."""

    def __init__(self, wall_p0, wall_n, deep=False):
        self._wall_p0, self._wall_n = wall_p0, wall_n
        # The pairs of a boundary element and any element of the other body too (the
        # potential law: pdfem.kernels.grain_depth)
        self.deep = deep
        self.gpairs = np.zeros((0, 2), np.int64)
        self.cand = np.zeros((0, 3), np.int64)
        self._out = np.zeros((1024, 3), np.int64)
        self._wall_out = np.zeros((2, 1024), np.int64)

    def rebuild(self, st, ctx):
        """Candidate grain pairs from the cell grid (first level of detection), then their
        element pairs and the owned grain elements near a wall, sorted by key (second)."""
        s, g0 = st.store, ctx.nglobal
        n = s.nbody - g0
        cent = np.empty((n, 2))
        body_centroids(s.x, s.nstart, s.nn, g0, s.nbody, cent)
        cells = ctx.grid.cell_of(cent) if n else np.zeros(0, np.int64)
        bbox = np.empty((s.nelem, 4))
        element_bboxes(s.x, s.conn, 0, s.nelem, bbox)
        boxes = np.empty((s.nbody, 4))
        body_boxes(bbox, s.estart, s.ne, 0, s.nbody, boxes)
        owned = (np.arange(g0, s.nbody) < s.nb_own).astype(np.int8)
        pairs = grain_pairs(cells.astype(np.int64), owned, boxes[g0:], ctx.grid.nx,
                            ctx.grid.ny, ctx.skin, st.reach, ctx.grid.period)
        pairs[:, :2] += g0
        self.gpairs = pairs[:, :2]
        reach = ctx.skin * (1.0 + REACH_SLACK)
        epairs = self._element_pairs(st, ctx, bbox, pairs, reach)
        welems, wids = self._wall_elements(st, ctx, bbox, block_elements(s, g0), s.ne_own, reach)
        cand = sorted_candidates(s, epairs, welems, wids)
        if ctx.grid.periodic_x:
            twice = repeated_pairs(cand)
            if twice:
                st.fail(f"periodic sides: {twice} element pair(s) within the skin of each "
                         "other through both sides of the box; widen domain.box")
        self.cand = self._with_blocks(st, ctx, cand, bbox, boxes, reach)

    def _with_blocks(self, st, ctx, cand, bbox, boxes, reach):
        """The grains' candidates merged in key order with the blocks' (element pairs and
        wall elements within reach)."""
        s, g0 = st.store, ctx.nglobal
        if g0 == 0:
            return cand
        pairs = self._element_pairs(st, ctx, bbox, self._block_pairs(st, ctx, boxes, reach),
                                    reach)
        welems, wids = self._wall_elements(st, ctx, bbox, 0, block_elements(s, g0), reach)
        blocks = sorted_candidates(s, pairs, welems, wids)
        out = np.empty((cand.shape[0] + blocks.shape[0], 3), np.int64)
        merge_candidates(cand, blocks, s.elem_gid, s.elem_loc, out)
        return out

    def _block_pairs(self, st, ctx, boxes, reach):
        """Owned grains within reach of each block, and the block pairs, with the block's
        period shift (each shift at which the boxes come within reach)."""
        s, g0, w = st.store, ctx.nglobal, ctx.grid.period
        parts = [np.zeros((0, 3), np.int64)]
        own = np.arange(g0, s.nb_own)
        for g in range(g0):
            b = boxes[g]
            rows = own[(boxes[own, 1] <= b[3] + reach) & (boxes[own, 3] >= b[1] - reach)]
            # The shifts that can bring the block's box within reach of a grain's (0 without a
            # period)
            k0 = k1 = 0
            if w > 0.0 and rows.size:
                k0 = math.ceil((boxes[rows, 0].min() - b[2] - reach) / w)
                k1 = math.floor((boxes[rows, 2].max() - b[0] + reach) / w)
            for k in range(k0, k1 + 1):
                near = rows[(boxes[rows, 0] <= b[2] + k * w + reach)
                            & (boxes[rows, 2] >= b[0] + k * w - reach)]
                parts.append(np.stack([near, np.full(near.shape[0], g),
                                       np.full(near.shape[0], k)], axis=1))
            for h in range(g + 1, g0):
                shifts = (-1, 0, 1) if w > 0.0 else (0,)
                parts.append(np.array([[g, h, k] for k in shifts], np.int64))
        return np.concatenate(parts).astype(np.int64)

    def _element_pairs(self, st, ctx, bbox, bpairs, reach):
        """Boundary-element pairs of the candidate bodies whose boxes are within reach (with
        deep, a boundary element and any element of the other body)."""
        s = st.store
        e0, e1 = s.estart, s.estart + s.ne
        while True:
            n = candidate_pairs(bbox, s.ebnd, s.elem_gid, s.elem_loc, e0, e1, bpairs, reach,
                                self.deep, ctx.grid.period, self._out)
            if n <= self._out.shape[0]:
                return self._out[:n].copy()
            self._out = np.zeros((2 * n, 3), np.int64)

    def _wall_elements(self, st, ctx, bbox, e0, e1, reach):
        """(elements, wall index) of the boundary elements of [e0, e1) within reach of a
        wall's half-plane."""
        s = st.store
        if not self._wall_p0.shape[0]:
            return np.zeros(0, np.int64), np.zeros(0, np.int64)
        while True:
            m = wall_crossings(bbox, s.ebnd, e0, e1, self._wall_p0, self._wall_n, reach,
                               self._wall_out[0], self._wall_out[1])
            if m <= self._wall_out.shape[1]:
                return self._wall_out[0, :m].copy(), self._wall_out[1, :m].copy()
            self._wall_out = np.zeros((2, 2 * m), np.int64)

    def step(self, st, ctx):
        """This step's candidates: those of the last rebuild, the blocks' among them."""
        return self.cand
