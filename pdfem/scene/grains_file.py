"""Reading ``[grains_file]``: a CSV with a header line, or a ``.npz`` of named arrays.

Columns x, y, a, b are required; angle, vx, vy and material are optional (a blank CSV cell
takes the default: angle 0, the table's velocity, the table's material). Errors name the
file and the line (CSV, counting from 1) or row (npz, counting from 0).
"""

import csv
import math
import zipfile
from pathlib import Path

import numpy as np

from pdfem.scene.values import SceneError, show

REQUIRED_COLUMNS = ("x", "y", "a", "b")
OPTIONAL_COLUMNS = ("angle", "vx", "vy", "material")
COLUMNS = REQUIRED_COLUMNS + OPTIONAL_COLUMNS


class GrainRows:
    """Grains read from a file: column arrays plus where each row came from."""

    def __init__(self, name, unit, where, arrays):
        self.name = name  # the path as written in the scene
        self.unit = unit  # "line" (CSV) or "row" (npz)
        self.where = where  # (n,) line or row number of each grain
        self.arrays = arrays  # center, axes, angle, velocity, material

    def label(self, k):
        """``grains.csv line 12`` for grain ``k`` of this file."""
        return f"{self.name} {self.unit} {int(self.where[k])}"


def read_grains_file(spec, base_dir, materials):
    """Read the file of a checked ``[grains_file]`` table; ``materials`` maps name -> id."""
    name = spec["path"]
    path = Path(base_dir, name)
    if not path.is_file():
        raise SceneError("grains_file.path", f"file not found: {path}")
    # A prepared bed (HDF5): columns plus the node positions and velocities of every grain
    if path.suffix.lower() in (".h5", ".hdf5"):
        return _bed_rows(path, name, spec, materials)
    # Read the raw columns
    if path.suffix.lower() == ".npz":
        cols, where, unit = _read_npz(path, name)
    else:
        cols, where, unit = _read_csv(path, name)
    n = where.shape[0]

    def at(k):
        return f"grains_file: {name} {unit} {int(where[k])}"

    # Fill optional columns, check ranges
    vx, vy = spec["velocity"]
    angle = _fill(cols.get("angle"), n, 0.0)
    vel = np.stack([_fill(cols.get("vx"), n, vx), _fill(cols.get("vy"), n, vy)], axis=1)
    for col in ("a", "b"):
        bad = np.nonzero(~(cols[col] > 0.0))[0]
        if bad.size:
            k = bad[0]
            raise SceneError(at(k), f"{col}: must be > 0 (got {show(float(cols[col][k]))})")
    # Material names -> ids
    mat = np.empty(n, np.int64)
    names = cols.get("material")
    default = spec.get("material")
    for k in range(n):
        m = names[k] if names is not None and names[k] != "" else default
        if m is None:
            raise SceneError(at(k), "material: none given and grains_file.material is not set")
        if m not in materials:
            raise SceneError(at(k), f"material: unknown material {show(m)} "
                             f"(known: {', '.join(materials)})")
        mat[k] = materials[m]
    arrays = {
        "center": np.stack([cols["x"], cols["y"]], axis=1),
        "axes": np.stack([cols["a"], cols["b"]], axis=1),
        "angle": angle,
        "velocity": vel,
        "material": mat,
    }
    return GrainRows(name, unit, where, arrays)


def _bed_rows(path, name, spec, materials):
    """GrainRows of a bed file: every grain of the spec's material, meshes as prepared."""
    from pdfem.io.bedfile import read_bed

    cols, nodes, vel, level, stress, state = read_bed(path, name)
    n = nodes.shape[0]
    if "material" not in spec:
        raise SceneError("grains_file.material", "required with a bed file")
    if spec["material"] not in materials:
        raise SceneError("grains_file.material", f"unknown material {show(spec['material'])}")
    arrays = {
        "center": nodes.mean(axis=1),
        "axes": np.stack([cols["a"], cols["b"]], axis=1),
        "angle": cols["angle"],
        "velocity": vel.mean(axis=1),
        "material": np.full(n, materials[spec["material"]], np.int64),
        "nodes": nodes,
        "node_v": vel,
    }
    if stress is not None:
        arrays["elem_sig"], arrays["elem_mst"] = stress, state
    rows = GrainRows(name, "row", np.arange(n, dtype=np.int64), arrays)
    rows.level = level
    return rows


def _fill(col, n, default):
    """An optional numeric column with NaN (blank) entries replaced by ``default``."""
    if col is None:
        return np.full(n, float(default))
    return np.where(np.isnan(col), float(default), col)


def _header(names, path_key):
    """Check a header: known, unique, complete."""
    for name in names:
        if name not in COLUMNS:
            raise SceneError(path_key, f"unknown column {show(name)} (known: "
                             f"{', '.join(COLUMNS)})")
        if names.count(name) > 1:
            raise SceneError(path_key, f"column {show(name)} appears twice")
    for name in REQUIRED_COLUMNS:
        if name not in names:
            raise SceneError(path_key, f"missing column {show(name)} (required: "
                             f"{', '.join(REQUIRED_COLUMNS)})")


def _read_csv(path, name):
    """Columns of a CSV file (blank lines and lines starting with # are skipped)."""
    try:
        text = path.read_text()
    except (OSError, UnicodeDecodeError) as exc:
        raise SceneError("grains_file.path", f"cannot read {path}: {exc}") from None
    lines = [(i + 1, s) for i, s in enumerate(text.splitlines())
             if s.strip() and not s.lstrip().startswith("#")]
    if not lines:
        raise SceneError("grains_file.path", f"{name} is empty (a header line is required)")
    # Header
    hline, htext = lines[0]
    header = [h.strip() for h in next(csv.reader([htext]))]
    _header(header, f"grains_file: {name} line {hline}")
    raw = {h: [] for h in header}
    where = np.array([ln for ln, _ in lines[1:]], np.int64)
    # Rows, converted cell by cell so an error can name its line
    body = lines[1:]
    for (ln, _), row in zip(body, csv.reader([s for _, s in body]), strict=True):
        if len(row) != len(header):
            raise SceneError(f"grains_file: {name} line {ln}",
                             f"expected {len(header)} fields (got {len(row)})")
        for h, cell in zip(header, row, strict=True):
            raw[h].append(_cell(cell.strip(), h, f"grains_file: {name} line {ln}"))
    cols = {h: (v if h == "material" else np.array(v, float).reshape(-1))
            for h, v in raw.items()}
    return cols, where, "line"


def _cell(cell, col, where):
    """One CSV cell: a finite float (NaN marks a blank optional cell) or a material name."""
    if col == "material":
        return cell
    if cell == "":
        if col in REQUIRED_COLUMNS:
            raise SceneError(where, f"{col}: empty field")
        return math.nan
    try:
        x = float(cell)
    except ValueError:
        raise SceneError(where, f"{col}: not a number (got {show(cell)})") from None
    if not math.isfinite(x):
        raise SceneError(where, f"{col}: must be finite (got {show(cell)})")
    return x


def _read_npz(path, name):
    """Columns of an .npz archive (no pickled objects)."""
    try:
        with np.load(path, allow_pickle=False) as npz:
            data = {k: npz[k] for k in npz.files}
    except (OSError, ValueError, zipfile.BadZipFile) as exc:
        msg = str(exc).splitlines()[0] if str(exc) else type(exc).__name__
        raise SceneError("grains_file.path", f"cannot read {path}: {msg}") from None
    _header(list(data), f"grains_file: {name}")
    n = data["x"].shape[0] if data["x"].ndim == 1 else -1
    cols = {}
    for h, arr in data.items():
        if arr.ndim != 1 or arr.shape[0] != n:
            raise SceneError(f"grains_file: {name}", f"array {h}: expected shape ({max(n, 0)},)"
                             f" like x (got {arr.shape})")
        if h == "material":
            if arr.dtype.kind not in "US":
                raise SceneError(f"grains_file: {name}", "array material: expected strings")
            cols[h] = [s.decode() if isinstance(s, bytes) else str(s) for s in arr.tolist()]
            continue
        if arr.dtype.kind not in "iuf":
            raise SceneError(f"grains_file: {name}", f"array {h}: expected numbers "
                             f"(got dtype {arr.dtype})")
        col = arr.astype(float)
        bad = np.nonzero(~np.isfinite(col))[0]
        if bad.size:
            raise SceneError(f"grains_file: {name} row {bad[0]}",
                             f"{h}: must be finite (got {show(float(col[bad[0]]))})")
        cols[h] = col
    return cols, np.arange(n, dtype=np.int64), "row"
