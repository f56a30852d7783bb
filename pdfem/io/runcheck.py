"""Checks of a run file before ``analyse`` or ``export`` reads it.

Every dataset of the layout (:mod:`pdfem.io.h5out`) that the caller uses must be numeric (not
strings, bytes, records or objects) and of its layout's shape: one row per frame (F rows, as
many as /frames/time), per node (NN, as /mesh/node_body) or per element (NE, as /mesh/conn).
Mesh ids must be in range (node ids in [0, NN), body ids in [0, NB), material ids >= 0 and
below the scene's count when known), and frame and gauge times finite and increasing (a run
writes at most one frame and one gauge sample a step, and every step moves the time on). The
first problem found raises :class:`~pdfem.errors.InputError` naming the file and the dataset.
The frame fields' values are not read (a run file may be larger than memory). Before the
command opens the file, :func:`pdfem.io.probe.check_metadata` has walked its metadata in a
child process (damaged metadata can hang or crash the HDF5 library).
"""

import h5py
import numpy as np

from pdfem.errors import InputError
from pdfem.io.layout import frame_layout

# Gauge series: the shape after the gauge-time row, and whether every gauge has it
GAUGE_SERIES = {"velocity": ((2,), True), "stress": ((4,), True), "force": ((2,), False)}
# What a dataset's numpy dtype kind holds, for the error message
KIND_NAMES = {"f": "floats", "S": "bytes", "U": "strings", "O": "objects (strings)", "V": "records",
              "b": "booleans", "c": "complex numbers", "M": "dates", "m": "time spans"}


def check_run_file(f, path, series=False, n_materials=None):
    """Check the open run file ``f`` (read from ``path``) before it is read; InputError if bad.

    Checks /mesh and /frames; with ``series`` also /gauges (required) and /energy (when
    present), the time series that ``analyse`` reads. ``n_materials`` (the scene's material
    count, when known) bounds /mesh/elem_material. Returns (F, NN, NE).
    """
    try:
        for group in ("frames", "mesh"):
            if not isinstance(f.get(group), h5py.Group):
                raise InputError(f"{path}: not a pdfem run file (no /frames or /mesh)")
        nn, ne = _check_mesh(f, path, n_materials)
        nf = _check_frames(f, path, nn, ne)
        if series:
            _check_gauges(f, path, ne)
            _check_energy(f, path)
    except (OSError, RuntimeError) as exc:
        # A damaged block of the file (h5py raises OSError or RuntimeError reading it)
        raise InputError(f"{path}: cannot read the run file ({_one_line(exc)})") from None
    return nf, nn, ne


def _one_line(exc):
    """An exception's message folded onto one line."""
    return " ".join(str(exc).split())


def _dataset(f, name, path):
    """The dataset ``name`` of ``f``; InputError when missing or not a dataset."""
    obj = f.get(name)
    if obj is None:
        raise InputError(f"{path}: /{name}: missing (not a complete pdfem run file)")
    if not isinstance(obj, h5py.Dataset):
        raise InputError(f"{path}: /{name}: a {type(obj).__name__.lower()}, not a dataset")
    return obj


def _dtype(d, name, path):
    """The numpy dtype of dataset d; InputError when h5py cannot map its HDF5 datatype (a
    damaged datatype message: a float of no numpy precision, say)."""
    try:
        return d.dtype
    except (ValueError, TypeError) as exc:
        msg = " ".join(str(exc).split())
        raise InputError(f"{path}: /{name}: unreadable datatype ({msg})") from None


def _numeric(d, name, path, ids=False):
    """InputError unless dataset d holds numbers (integers when ``ids``)."""
    dtype = _dtype(d, name, path)
    kind = dtype.kind
    want = "iu" if ids else "iuf"
    if kind not in want:
        held = KIND_NAMES.get(kind, f"dtype {dtype}")
        what = "integer ids" if ids else "numbers"
        raise InputError(f"{path}: /{name}: holds {held}, not {what}")


def _floats(d, name, path):
    """InputError unless dataset d holds floats (what the run writes for a frame field)."""
    dtype = _dtype(d, name, path)
    if dtype.kind != "f":
        held = KIND_NAMES.get(dtype.kind, f"integers ({dtype})" if dtype.kind in "iu"
                              else f"dtype {dtype}")
        raise InputError(f"{path}: /{name}: holds {held}, not floats")


def _shaped(d, name, path, want, rows):
    """InputError unless d.shape is ``want`` (None matches any length); ``rows`` says what
    the leading axes count, for the message."""
    ok = len(d.shape) == len(want) and all(
        w is None or n == w for n, w in zip(d.shape, want, strict=True))
    if not ok:
        shown = str(tuple(-1 if w is None else w for w in want)).replace("-1", "any")
        raise InputError(f"{path}: /{name}: shape {d.shape}, expected {shown} ({rows})")


def _read(d, name, path):
    """All of dataset d as an array; InputError when HDF5 cannot read it."""
    try:
        return d[()]
    except (OSError, ValueError, TypeError) as exc:
        msg = " ".join(str(exc).split())
        raise InputError(f"{path}: /{name}: cannot read ({msg})") from None


def _in_range(d, name, path, n, what):
    """InputError unless every value of the integer dataset d is in [0, n) (n None: >= 0)."""
    a = _read(d, name, path)
    bad = np.argwhere((a < 0) if n is None else (a < 0) | (a >= n))
    if bad.size:
        limit = f"[0, {n})" if n is not None else ">= 0"
        raise InputError(f"{path}: /{name}: {what} {int(a[tuple(bad[0])])} at row "
                         f"{int(bad[0][0])} out of range {limit}")


def _times(d, name, path):
    """InputError unless the times of dataset d are finite and increasing."""
    t = _read(d, name, path).astype(float)
    bad = np.flatnonzero(~np.isfinite(t))
    if bad.size:
        raise InputError(f"{path}: /{name}: not finite at row {int(bad[0])} "
                         f"(got {float(t[bad[0]])!r})")
    back = np.flatnonzero(np.diff(t) <= 0.0)
    if back.size:
        k = int(back[0]) + 1
        how = "decreases" if t[k] < t[k - 1] else "repeats"
        raise InputError(f"{path}: /{name}: {how} at row {k} "
                         f"({float(t[k])!r} after {float(t[k - 1])!r})")


def _check_mesh(f, path, n_materials):
    """/mesh: integer ids of the layout's shapes, in range; returns (NN, NE)."""
    dsets = {n: _dataset(f, f"mesh/{n}", path)
             for n in ("body_kind", "node_body", "conn", "elem_body", "elem_material")}
    for n, d in dsets.items():
        _numeric(d, f"mesh/{n}", path, ids=True)
    # The counts: bodies, nodes and elements
    _shaped(dsets["body_kind"], "mesh/body_kind", path, (None,), "one row per body")
    _shaped(dsets["node_body"], "mesh/node_body", path, (None,), "one row per node")
    _shaped(dsets["conn"], "mesh/conn", path, (None, 4), "four node ids per element")
    nb, nn, ne = (dsets[n].shape[0] for n in ("body_kind", "node_body", "conn"))
    for n in ("elem_body", "elem_material"):
        _shaped(dsets[n], f"mesh/{n}", path, (ne,), "one row per element of /mesh/conn")
    # The ids
    _in_range(dsets["body_kind"], "mesh/body_kind", path, 2, "body kind (0 grain, 1 block)")
    _in_range(dsets["node_body"], "mesh/node_body", path, nb, "body id")
    _in_range(dsets["conn"], "mesh/conn", path, nn, "node id")
    _in_range(dsets["elem_body"], "mesh/elem_body", path, nb, "body id")
    _in_range(dsets["elem_material"], "mesh/elem_material", path, n_materials, "material id")
    return nn, ne


def _check_frames(f, path, nn, ne):
    """/frames: times, then every frame field present (x required); returns F."""
    d = _dataset(f, "frames/time", path)
    _numeric(d, "frames/time", path)
    _shaped(d, "frames/time", path, (None,), "one row per frame")
    _times(d, "frames/time", path)
    nf = d.shape[0]
    _dataset(f, "frames/x", path)
    fr = f["frames"]
    for field, (per, tail) in frame_layout().items():
        if field not in fr:
            continue
        name = f"frames/{field}"
        d = _dataset(f, name, path)
        _floats(d, name, path)
        rows = nn if per == "node" else ne
        what = "nodes" if per == "node" else "elements"
        _shaped(d, name, path, (nf, rows) + tail, f"{nf} frames of /frames/time by {rows} {what}")
    return nf


def _check_gauges(f, path, ne):
    """/gauges: its time axis and each gauge's series of as many rows; element ids in range."""
    if not isinstance(f.get("gauges"), h5py.Group):
        raise InputError(f"{path}: /gauges: missing (the run has no [[gauges]])")
    d = _dataset(f, "gauges/time", path)
    _numeric(d, "gauges/time", path)
    _shaped(d, "gauges/time", path, (None,), "one row per gauge sample")
    _times(d, "gauges/time", path)
    ng = d.shape[0]
    for gauge, g in f["gauges"].items():
        if gauge == "time":
            continue
        if not isinstance(g, h5py.Group):
            raise InputError(f"{path}: /gauges/{gauge}: a dataset, not a gauge group")
        for series, (tail, required) in GAUGE_SERIES.items():
            name = f"gauges/{gauge}/{series}"
            if not required and series not in g:
                continue
            d = _dataset(f, name, path)
            _numeric(d, name, path)
            _shaped(d, name, path, (ng,) + tail, "one row per sample of /gauges/time")
        if "elements" in g:
            name = f"gauges/{gauge}/elements"
            d = _dataset(f, name, path)
            _numeric(d, name, path, ids=True)
            _shaped(d, name, path, (None,), "a list of element ids")
            _in_range(d, name, path, ne, "element id")


def _check_energy(f, path):
    """/energy, when present: numeric series, all as long as the first (/energy/time)."""
    if "energy" not in f:
        return
    if not isinstance(f["energy"], h5py.Group):
        raise InputError(f"{path}: /energy: a dataset, not a group")
    n = None
    # The time axis first: the other series have one row per energy sample
    for term in sorted(f["energy"], key=lambda t: t != "time"):
        name = f"energy/{term}"
        d = _dataset(f, name, path)
        _numeric(d, name, path)
        _shaped(d, name, path, (n,), "one row per sample of /energy/time")
        n = d.shape[0]
