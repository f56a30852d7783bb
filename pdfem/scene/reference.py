"""The scene-file reference (docs/scene/), generated from the schema tables.

``python -m pdfem.scene.reference --out docs/scene`` writes one page per table,
``docs/scene/<table>.md``, and the index ``docs/scene/README.md``; a test checks that the pages
on disk are exactly these, so the documentation cannot drift from the code.
"""

import math

from pdfem.scene import schema as S

_TYPES = {"float": "float", "int": "int", "str": "string", "bool": "true or false",
          "vec2": "[float, float]", "box": "[float, float, float, float]",
          "strlist": "list of strings"}

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
    if isinstance(d, bool):
        return "true" if d else "false"
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


# Where each table's physics or use is explained (paths relative to docs/scene/)
READING = {
    "domain": [("the step and the domain decomposition", "../theory/step.md")],
    "time": [("the step and its stable time step", "../theory/step.md")],
    "element": [("the element", "../theory/element.md")],
    "gravity": [("the step", "../theory/step.md")],
    "damping": [("the step", "../theory/step.md")],
    "bulk_viscosity": [("bulk viscosity", "../theory/element.md")],
    "materials": [("the cap model", "../theory/cap.md"),
                  ("the equation of state", "../theory/eos.md")],
    "grains": [("scenes by example", "../user/scenes.md")],
    "grains_file": [("scenes by example", "../user/scenes.md"),
                    ("preparing a bed", "../user/prepare.md")],
    "blocks": [("scenes by example", "../user/scenes.md")],
    "bc": [("scenes by example", "../user/scenes.md")],
    "walls": [("contact", "../theory/contact.md")],
    "contact": [("contact", "../theory/contact.md"),
                ("the energy balance", "../theory/energy.md")],
    "heat": [("heat", "../theory/heat.md")],
    "conduction": [("heat", "../theory/heat.md")],
    "dissipation_heating": [("heat", "../theory/heat.md"),
                            ("the energy balance", "../theory/energy.md")],
    "viscous_heating": [("heat", "../theory/heat.md"),
                        ("the energy balance", "../theory/energy.md")],
    "thermoelastic": [("heat", "../theory/heat.md"),
                      ("the energy balance", "../theory/energy.md")],
    "thermal_expansion": [("heat", "../theory/heat.md"),
                          ("the energy balance", "../theory/energy.md")],
    "temperature_dependence": [("heat", "../theory/heat.md")],
    "contact_conductance": [("heat", "../theory/heat.md")],
    "friction_heating": [("heat", "../theory/heat.md"),
                         ("the energy balance", "../theory/energy.md")],
    "thermal_bc": [("heat", "../theory/heat.md")],
    "gauges": [("the run file", "../user/output.md")],
    "shock": [("shot 912: how the wave is measured", "../validation/shot912.md")],
    "prepare": [("preparing a bed", "../user/prepare.md")],
    "output": [("the run file", "../user/output.md"),
               ("checkpoints and restarts", "../user/checkpoints.md")],
    "guards": [("guards and remedies", "../validation/hard-cases.md"),
               ("bad input and exit codes", "../user/bad-input.md")],
    "run": [],
}


def _title(sec):
    """``[name]`` with its tags: (required), (effect)."""
    tags = [t for t, on in (("required", sec.required),
                            ("effect", (sec.name in S.PRESENCE_TABLES
                                        and sec.name not in ("walls", "grains_file"))
                             or sec in S.EFFECT_SECTIONS))
            if on]
    suffix = f" ({', '.join(tags)})" if tags else ""
    return f"`{_heading(sec)}`{suffix}"


def _page(sec):
    """The page of one table: its doc, its keys, its sub-tables, where to read more."""
    lines = [f"# {_title(sec)}", "",
             "Generated from `pdfem/scene/schema.py` by `python -m pdfem.scene.reference "
             "--out docs/scene`; [all tables](README.md).", "",
             sec.doc, ""] + _rows(sec.keys) + [""]
    # Per-model material keys and contact pairs
    if sec.name == "materials":
        for model, keys in S.MATERIAL_MODELS.items():
            if keys:
                lines += [f'## `[materials.NAME]` with `model = "{model}"`', "",
                          "Additional keys of this model (keys of other models are "
                          "errors).", ""] + _rows(keys) + [""]
    if sec.name == "contact":
        lines += ['## `[contact.pairs."mat1:mat2"]`', "",
                  "Overrides for contacts between two materials (either order, each "
                  "pair once).", ""] + _rows(S.CONTACT_PAIR) + [""]
    links = READING.get(sec.name, [])
    if links:
        lines += ["Read more: " + ", ".join(f"[{t}]({u})" for t, u in links) + "."]
    return "\n".join(lines).rstrip("\n") + "\n"


def _index():
    """docs/scene/README.md: the rules every scene obeys and the list of tables."""
    lines = [_INTRO.rstrip("\n"), "",
             "Generated from `pdfem/scene/schema.py` by `python -m pdfem.scene.reference "
             "--out docs/scene`. Examples of whole scenes: [scenes by example]"
             "(../user/scenes.md).", "",
             "| table | what it is |", "|---|---|"]
    for sec in S.all_sections():
        first = sec.doc.split(". ")[0].rstrip(".").replace("|", "\\|")
        lines.append(f"| [{_title(sec)}]({sec.name}.md) | {first}. |")
    return "\n".join(lines) + "\n"


def pages():
    """Every page of the reference: file name in docs/scene/ -> Markdown text."""
    out = {"README.md": _index()}
    for sec in S.all_sections():
        out[f"{sec.name}.md"] = _page(sec)
    return out


if __name__ == "__main__":
    import argparse
    from pathlib import Path

    ap = argparse.ArgumentParser(prog="python -m pdfem.scene.reference",
                                 description="write the scene reference, one page per table")
    ap.add_argument("--out", required=True, type=Path,
                    help="folder of the pages (docs/scene); existing pages are replaced")
    args = ap.parse_args()
    args.out.mkdir(parents=True, exist_ok=True)
    for name, text in pages().items():
        (args.out / name).write_text(text)
