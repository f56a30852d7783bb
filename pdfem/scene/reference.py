"""The scene-file reference (docs/scene-reference.md), generated from the schema tables.

``python -m pdfem.scene.reference > docs/scene-reference.md`` regenerates it and
``python -m pdfem.scene.reference --readme`` rewrites the same text between the README's
scene-reference markers; a test checks both, so the documentation cannot drift from the code.
"""

import math

from pdfem.scene import schema as S

_TYPES = {"float": "float", "int": "int", "str": "string", "vec2": "[float, float]",
          "box": "[float, float, float, float]", "strlist": "list of strings"}

_INTRO = """\
# Scene file reference

A scene is a TOML file, one table per component, SI units throughout. Unknown tables and
keys, wrong types, values out of range, NaN and infinities (except `time.dt_max = inf`) and
impossible geometry are rejected before the first step, with exit status 2 and a one-line
message that names the file and the key, e.g.
`bed.toml: time.end: must be > 0 (got -1.0)` or `bed.toml: grains[3]: overlaps grains[7] at t=0`.
Indices count from 0. Integers are accepted where a float is expected, not the other way round.

Defaults: *required* keys must be given; *absent* keys stay absent unless given; all other
defaults are filled into the **resolved scene**, which is stored in every output file and
can be read back as a scene (`Scene.to_toml_string()`); derived defaults (auto cell size and
skin, intervals, the cap tension cut-off, boundary-condition dof) are stored as the values
computed. Tables marked *effect* exist in a run only when present in the scene; so do
`[walls]` and `[grains_file]`.

Geometry at t=0: every grain's bounding box and every block lie inside `domain.box`; no two
grains, no grain and block, and no two blocks overlap (blocks may touch). Grains are tested as
polygons of 64 points on the ellipse inflated by a relative 1e-9, so touching grains count
as overlapping.
"""


def _default(key):
    """The default column: a TOML value, *required*, *absent* or how it is derived."""
    d = key.default
    if d is S.REQUIRED:
        return "*required*"
    if d is S.OPTIONAL:
        return "*absent*"
    if isinstance(d, S.Derived):
        return d.text
    if isinstance(d, float) and math.isinf(d):
        return "inf"
    if isinstance(d, str):
        return f'"{d}"'
    if isinstance(d, list):
        return "[" + ", ".join(f'"{x}"' if isinstance(x, str) else repr(x) for x in d) + "]"
    return repr(d)


def _rows(keys):
    """Markdown table of keys: key, type, default, range, meaning, units."""
    out = ["| key | type | default | range | meaning | units |",
           "|---|---|---|---|---|---|"]
    for name, key in keys.items():
        cells = [f"`{name}`", _TYPES[key.kind], _default(key), key.range_text(), key.doc,
                 key.units]
        out.append("| " + " | ".join(c.replace("|", "\\|") for c in cells) + " |")
    return out


def _heading(sec):
    """``[name]``, ``[[name]]`` or ``[name.NAME]``."""
    return {"table": f"[{sec.name}]", "array": f"[[{sec.name}]]",
            "named": f"[{sec.name}.NAME]"}[sec.form]


def markdown():
    """The whole reference as Markdown text."""
    lines = [_INTRO]
    for sec in S.SECTIONS:
        tags = [t for t, on in (("required", sec.required),
                                ("effect", sec.name in S.PRESENCE_TABLES
                                 and sec.name not in ("walls", "grains_file")))
                if on]
        suffix = f" ({', '.join(tags)})" if tags else ""
        lines += [f"## `{_heading(sec)}`{suffix}", "", sec.doc, ""] + _rows(sec.keys) + [""]
        # Per-model material keys and contact pairs
        if sec.name == "materials":
            for model, keys in S.MATERIAL_MODELS.items():
                if keys:
                    lines += [f'### `[materials.NAME]` with `model = "{model}"`', "",
                              "Additional keys of this model (keys of other models are "
                              "errors).", ""] + _rows(keys) + [""]
        if sec.name == "contact":
            lines += ['### `[contact.pairs."mat1:mat2"]`', "",
                      "Overrides for contacts between two materials (either order, each "
                      "pair once).", ""] + _rows(S.CONTACT_PAIR) + [""]
    return "\n".join(lines).rstrip("\n") + "\n"


# The README section the reference is copied into
README_BEGIN = ("<!-- scene-reference:begin (generated: python -m pdfem.scene.reference "
                "--readme) -->")
README_END = "<!-- scene-reference:end -->"


def readme_section(text):
    """The generated part of a README text (between the markers), or None."""
    if README_BEGIN not in text or README_END not in text:
        return None
    return text.split(README_BEGIN, 1)[1].split(README_END, 1)[0]


def readme_body():
    """What goes between the README markers: the reference, its headings one level down."""
    lines = markdown().splitlines()[1:]
    return "\n" + "\n".join("#" + ln if ln.startswith("#") else ln for ln in lines) + "\n"


if __name__ == "__main__":
    import sys
    from pathlib import Path

    if sys.argv[1:] == ["--readme"]:
        path = Path(__file__).resolve().parents[2] / "README.md"
        text = path.read_text()
        head, rest = text.split(README_BEGIN, 1)
        tail = rest.split(README_END, 1)[1]
        path.write_text(head + README_BEGIN + readme_body() + README_END + tail)
    else:
        print(markdown(), end="")
