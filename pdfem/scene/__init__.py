"""Scene files: the TOML schema, defaults and validation of a pdfem run.

``load_scene(path)`` and ``parse_scene(text_or_dict, base_dir)`` return a :class:`Scene`;
every problem raises :class:`~pdfem.errors.InputError` with a one-line message naming the
file and the key path (``bed.toml: time.end: must be > 0 (got -1.0)``). The schema itself
lives in :mod:`pdfem.scene.schema`; docs/scene-reference.md is generated from it by
``python -m pdfem.scene.reference``.
"""

import tomllib
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from pdfem.errors import InputError
from pdfem.scene.toml_out import dumps
from pdfem.scene.validate import resolve
from pdfem.scene.values import SceneError

__all__ = ["Scene", "load_scene", "parse_scene"]


@dataclass(eq=False)
class Scene:
    """A checked scene.

    resolved: the full nested dict, every default filled in (stored in every output file).
    path: the scene file (None when parsed from text); base_dir: where relative input paths
    start. grains: dict of arrays center (n, 2), axes (n, 2), angle (n,), velocity (n, 2),
    material (n,) int64 ids; grains are ids 0..n-1, [[grains]] first, then grains_file rows.
    materials: material name -> id, in id order. blocks, bcs: the resolved [[blocks]] and
    [[bc]] lists.
    """

    resolved: dict
    path: Path | None
    base_dir: Path
    grains: dict
    materials: dict
    blocks: list
    bcs: list

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
    except (OSError, UnicodeDecodeError) as exc:
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
        resolved, grains, mat_ids, _ = resolve(doc, base)
    except SceneError as exc:
        raise InputError(f"{name}: {_one_line(exc)}") from None
    for k in ("center", "axes", "angle", "velocity"):
        grains[k] = np.ascontiguousarray(grains[k], dtype=np.float64)
    return Scene(resolved=resolved, path=None if path is None else Path(path), base_dir=base,
                 grains=grains, materials=mat_ids, blocks=resolved["blocks"],
                 bcs=resolved["bc"])


def _one_line(exc):
    """An exception's message folded onto one line."""
    return " ".join(str(exc).split())
