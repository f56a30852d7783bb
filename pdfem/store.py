"""The rank-local body store: structure of arrays, owned bodies first, ghosts at the tail.

Bodies are grains (owned by one rank, ghosted on its neighbours) and global bodies (blocks
such as the hammer and the chamber bottom, held and integrated identically on every rank).
Order of bodies on a rank: global bodies by gid, owned grains by gid, then ghost grains by
(source rank, gid). Each body's nodes and elements are contiguous and in its own mesh order,
so every kernel that loops in array order adds into a node in the same order on any number
of ranks. A body's whole state travels as a :class:`Batch` when it migrates.
"""

from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from pdfem.kernels.element_1pt import HG_COLS

# Field kinds: one row per body, per node, per element or per contact-history entry
BODY, NODE, ELEM, PAIR = "body", "node", "elem", "pair"
# The hourglass reference of a run without one (2x2 rule): no element has hourglass control
NO_HOURGLASS = np.zeros((0, HG_COLS))


@dataclass(frozen=True)
class Field:
    """One state array: name, kind, trailing shape and dtype."""

    name: str
    kind: str
    shape: tuple
    dtype: type


def core_fields(nip, nst, nacc, hg_cols=HG_COLS):
    """The fields every run has, and the 1-point rule's hourglass reference (hgref, hg_cols
    columns: pdfem.kernels.element_1pt); effects add their own (temperature, ...)."""
    hourglass = [Field("hgref", ELEM, (hg_cols,), np.float64)] if nip == 1 else []
    return [
        Field("gid", BODY, (), np.int64),
        Field("nn", BODY, (), np.int64),
        Field("ne", BODY, (), np.int64),
        Field("isglobal", BODY, (), np.int8),
        Field("acc", BODY, (nacc,), np.float64),
        Field("x", NODE, (2,), np.float64),
        Field("v", NODE, (2,), np.float64),
        Field("m", NODE, (), np.float64),
        Field("bcf", NODE, (2,), np.int8),
        Field("bcv", NODE, (2,), np.float64),
        Field("lconn", ELEM, (4,), np.int64),
        Field("emat", ELEM, (), np.int32),
        Field("ebnd", ELEM, (4,), np.int8),
        Field("elen", ELEM, (), np.float64),
        Field("sig", ELEM, (nip, 4), np.float64),
        Field("mst", ELEM, (nip, nst), np.float64),
    ] + hourglass + [
        Field("ewint", ELEM, (), np.float64),
        Field("ewp", ELEM, (), np.float64),
        Field("hkey", PAIR, (4,), np.int64),
        Field("hval", PAIR, (), np.float64),
    ]


class Batch:
    """State of a set of bodies (any order), as plain arrays keyed by field name."""

    def __init__(self, fields, arrays):
        self.fields = fields
        self.a = arrays

    @classmethod
    def empty(cls, fields):
        """A batch holding no body."""
        return cls(fields, {f.name: np.zeros((0,) + f.shape, f.dtype) for f in fields})

    @property
    def nbody(self):
        return self.a["gid"].shape[0]

    def to_buffer(self):
        """Flatten into one float64 buffer (integers are exact below 2**53)."""
        head = [float(self.nbody), float(self.a["hkey"].shape[0])]
        parts = [np.array(head)]
        parts += [self.a[f.name].astype(np.float64).ravel() for f in self.fields]
        return np.concatenate(parts)

    @classmethod
    def from_buffer(cls, fields, buf):
        """Inverse of :meth:`to_buffer`; returns the batch and the number of values used."""
        nb, nh = int(buf[0]), int(buf[1])
        pos = 2
        arrays = {}
        counts = {BODY: nb, PAIR: nh}
        for f in fields:
            if f.kind == NODE and NODE not in counts:
                counts[NODE] = int(arrays["nn"].sum())
            if f.kind == ELEM and ELEM not in counts:
                counts[ELEM] = int(arrays["ne"].sum())
            shape = (counts[f.kind],) + f.shape
            size = int(np.prod(shape))
            arrays[f.name] = buf[pos : pos + size].reshape(shape).astype(f.dtype)
            pos += size
        return cls(fields, arrays), pos

    @staticmethod
    def concat(fields, batches):
        """Concatenate batches in the given order."""
        return Batch(fields, {f.name: np.concatenate([b.a[f.name] for b in batches])
                              for f in fields})


def ranges(start, count):
    """Concatenated index ranges [start[i], start[i]+count[i]) as one int64 array."""
    count = np.asarray(count, np.int64)
    total = int(count.sum())
    if total == 0:
        return np.zeros(0, np.int64)
    rep = np.repeat(np.asarray(start, np.int64) - np.concatenate(([0], np.cumsum(count)[:-1])),
                    count)
    return rep + np.arange(total, dtype=np.int64)


class Store:
    """Rank-local arrays of every field plus the derived offsets the kernels need.

    Attributes named after fields hold the arrays (``store.x``, ``store.sig`` ...).
    ``nb_own``/``nn_own``/``ne_own`` count the global and owned bodies, nodes, elements: the
    ranges kernels update. Everything past them is ghost data refreshed by the halo.
    """

    if TYPE_CHECKING:
        # The field arrays are set by name (store.x, store.sig ...): what a checker sees
        def __getattr__(self, name: str) -> np.ndarray: ...

    def __init__(self, fields, batch, nb_own):
        self.fields = fields
        for f in fields:
            setattr(self, f.name, np.ascontiguousarray(batch.a[f.name]))
        self.nb_own = int(nb_own)
        self._derive()

    def _derive(self):
        # Offsets of each body's nodes and elements, and the rank-local connectivity
        self.nstart = np.concatenate(([0], np.cumsum(self.nn)[:-1])).astype(np.int64)
        self.estart = np.concatenate(([0], np.cumsum(self.ne)[:-1])).astype(np.int64)
        self.nnode = int(self.nn.sum())
        self.nelem = int(self.ne.sum())
        self.nn_own = int(self.nn[: self.nb_own].sum())
        self.nn_global = int(self.nn[self.isglobal == 1].sum())
        self.ne_own = int(self.ne[: self.nb_own].sum())
        self.node_body = np.repeat(np.arange(self.nbody, dtype=np.int64), self.nn)
        self.elem_body = np.repeat(np.arange(self.nbody, dtype=np.int64), self.ne)
        self.conn = self.lconn + self.nstart[self.elem_body][:, None]
        self.elem_gid = self.gid[self.elem_body]
        self.elem_loc = np.arange(self.nelem, dtype=np.int64) - self.estart[self.elem_body]
        self.xref = self.x.copy()
        # The element kernels' hourglass reference: hgref for the 1-point rule, else none
        self.hourglass = next((self.hgref for f in self.fields if f.name == "hgref"),
                              NO_HOURGLASS)

    @property
    def nbody(self):
        return self.gid.shape[0]

    def take(self, bodies, with_history=True):
        """Batch of the given local body indices (in that order), with their history rows."""
        bodies = np.asarray(bodies, np.int64)
        nidx = ranges(self.nstart[bodies], self.nn[bodies])
        eidx = ranges(self.estart[bodies], self.ne[bodies])
        if with_history and self.hkey.shape[0]:
            gids = self.gid[bodies]
            hidx = np.nonzero(np.isin(self.hkey[:, 0], gids) | np.isin(self.hkey[:, 2], gids))[0]
        else:
            hidx = np.zeros(0, np.int64)
        idx = {BODY: bodies, NODE: nidx, ELEM: eidx, PAIR: hidx}
        return Batch(self.fields, {f.name: getattr(self, f.name)[idx[f.kind]]
                                   for f in self.fields})
