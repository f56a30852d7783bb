"""Scene files: the TOML schema, defaults and validation of a pdfem run.

``load_scene(path)`` and ``parse_scene(text_or_dict, base_dir)`` return a :class:`Scene`;
every problem raises :class:`~pdfem.errors.InputError` with a one-line message naming the
file and the key path (``bed.toml: time.end: must be > 0 (got -1.0)``). The schema itself
lives in :mod:`pdfem.scene.schema`; docs/scene/ is generated from it by
``python -m pdfem.scene.reference --out docs/scene``.
"""

import math
import tomllib
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from pdfem.errors import InputError
from pdfem.scene.toml_out import dumps
from pdfem.scene.validate import resolve
from pdfem.scene.values import SceneError

__all__ = ["Scene", "check_ranks", "load_scene", "parse_scene"]

# Problem sizes beyond which a scene is refused (a typo, not a run: memory would run out)
MAX_CELLS = 10**7
MAX_BLOCK_ELEMENTS = 10**7
MAX_GRAINS = 10**7
# Initial and prescribed speeds must be below the speed of light [m/s] (larger ones are typos
# and overflow the kinetic energy)
LIGHT_SPEED = 299792458.0


@dataclass(eq=False)
class Scene:
    """A checked scene.

    resolved: the full nested dict, every default filled in (stored in every output file).
    path: the scene file (None when parsed from text); base_dir: where relative input paths
    start. grains: dict of arrays center (n, 2), axes (n, 2), angle (n,), velocity (n, 2),
    material (n,) int64 ids; grains are ids 0..n-1, [[grains]] first, then grains_file rows.
    materials: material name -> id, in id order. blocks, bcs: the resolved [[blocks]] and
    [[bc]] lists. name: what error messages call the scene (its file name, or the name it was
    parsed under).
    """

    resolved: dict
    path: Path | None
    base_dir: Path
    grains: dict
    materials: dict
    blocks: list
    bcs: list
    name: str = "<scene>"

    @property
    def n_grains(self):
        """Number of grains."""
        return int(self.grains["center"].shape[0])

    def to_toml_string(self):
        """The resolved scene as TOML text; ``parse_scene`` of it gives the same scene."""
        return dumps(self.resolved, header="pdfem resolved scene (every default filled in)")


def load_scene(path):
    """Read and check a scene file; relative paths inside it start at its directory."""
    path = Path(path)
    try:
        text = path.read_text()
    except (OSError, UnicodeDecodeError, ValueError) as exc:
        # ValueError: a NUL byte in the name
        reason = exc.strerror if isinstance(exc, OSError) and exc.strerror else str(exc)
        raise InputError(f"{path}: cannot read the scene file: {reason}") from None
    return parse_scene(text, path.parent, name=str(path), path=path)


def parse_scene(text_or_dict, base_dir=".", name="<scene>", path=None):
    """Check a scene given as TOML text or as the dict ``tomllib`` would make of it.

    ``name`` prefixes error messages (the file name); ``base_dir`` resolves grains_file.path.
    """
    # TOML syntax
    if isinstance(text_or_dict, str):
        try:
            doc = tomllib.loads(text_or_dict)
        except tomllib.TOMLDecodeError as exc:
            raise InputError(f"{name}: TOML syntax: {_one_line(exc)}") from None
    else:
        doc = text_or_dict
    # Schema, defaults, geometry
    base = Path(base_dir)
    try:
        resolved, grains, mat_ids, label = resolve(doc, base)
    except SceneError as exc:
        raise InputError(f"{name}: {_one_line(exc)}") from None
    _check_sizes(resolved, name)
    _check_speeds(resolved, grains, label, name)
    for k in ("center", "axes", "angle", "velocity"):
        grains[k] = np.ascontiguousarray(grains[k], dtype=np.float64)
    return Scene(resolved=resolved, path=None if path is None else Path(path), base_dir=base,
                 grains=grains, materials=mat_ids, blocks=resolved["blocks"],
                 bcs=resolved["bc"], name=name)


def grid_shape(resolved):
    """(nx, ny) of the contact cell grid of a resolved scene, as partition.CellGrid makes it
    (floats: a huge grid is reported, not allocated)."""
    x0, y0, x1, y1 = resolved["domain"]["box"]
    h = resolved["domain"]["cell_size"]
    return tuple(max(1.0, float(math.floor(q))) if math.isfinite(q) else q
                 for q in ((x1 - x0) / h, (y1 - y0) / h))


def _check_sizes(r, name):
    """Cell grid, block meshes and rained grains within what a run can hold."""
    nx, ny = grid_shape(r)
    if not nx * ny <= MAX_CELLS:
        raise InputError(f"{name}: domain.cell_size: the cell grid would have {nx * ny:.3g} "
                         f"cells ({nx:.3g} x {ny:.3g}), more than {MAX_CELLS:.0e}: use a larger "
                         "cell_size or a smaller domain.box")
    for i, b in enumerate(r["blocks"]):
        if not b["nx"] * b["ny"] <= MAX_BLOCK_ELEMENTS:
            raise InputError(f"{name}: blocks[{i}].nx: {b['nx']} x {b['ny']} elements, more "
                             f"than {MAX_BLOCK_ELEMENTS:.0e}")
    pr = r.get("prepare", {})
    if pr.get("grains", 0) > MAX_GRAINS:
        raise InputError(f"{name}: prepare.grains: must be <= {MAX_GRAINS:.0e} (got "
                         f"{pr['grains']})")
    if "height" in pr:
        # The most grains a geometric bed of this size can hold (smallest grains)
        x0, _, x1, _ = r["domain"]["box"]
        a = pr["semi_axis"][0]
        small = math.pi * a * a * pr["aspect"][0]
        if not math.isfinite(small):
            raise InputError(f"{name}: prepare.semi_axis: grains of {a:g} m have no finite "
                             "area")
        most = pr["packing"] * (x1 - x0) * pr["height"] / small
        if not most <= MAX_GRAINS:
            raise InputError(f"{name}: prepare.height: a bed this size could hold {most:.3g} "
                             f"grains, more than {MAX_GRAINS:.0e}")


def _check_speeds(r, grains, label, name):
    """Every velocity of the scene below the speed of light."""
    given = [(f"blocks[{i}].velocity", b["velocity"]) for i, b in enumerate(r["blocks"])]
    given += [(f"bc[{i}].velocity", b["velocity"]) for i, b in enumerate(r["bc"])
              if "velocity" in b]
    if "prepare" in r:
        given.append(("prepare.drop_velocity", [r["prepare"]["drop_velocity"]]))
    fast = np.nonzero(~(np.abs(grains["velocity"]) < LIGHT_SPEED).all(axis=1))[0]
    if fast.size:
        given.insert(0, (f"{label(int(fast[0]))}: velocity",
                         grains["velocity"][fast[0]].tolist()))
    for where, v in given:
        if not all(abs(c) < LIGHT_SPEED for c in v):
            raise InputError(f"{name}: {where}: must be below the speed of light "
                             f"{LIGHT_SPEED:.6g} m/s (got {v})")


def check_ranks(scene, nranks, name=None):
    """Every rank needs a cell of the grid: InputError naming domain.cell_size otherwise."""
    nx, ny = grid_shape(scene.resolved)
    if nranks > nx * ny:
        raise InputError(f"{name or scene.path}: domain.cell_size: the cell grid has "
                         f"{int(nx * ny)} cell(s) ({int(nx)} x {int(ny)}), fewer than the "
                         f"{nranks} ranks: start fewer ranks or use a smaller cell_size")


def _one_line(exc):
    """An exception's message folded onto one line."""
    return " ".join(str(exc).split())
