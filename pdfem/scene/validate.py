"""From a parsed TOML document to the resolved scene: every table checked, defaults filled.

:func:`resolve` checks the tables one by one against :mod:`pdfem.scene.schema`, applies the
rules that tie keys together (cap envelope, boundary conditions, derived defaults) and
finally the geometry at t=0 (:mod:`pdfem.scene.geometry`). Any problem raises
:class:`~pdfem.scene.values.SceneError` naming the key path.
"""

import math
import os
import re
from pathlib import Path

from pdfem.scene import schema as S
from pdfem.scene.cap import envelope_apex, strength_rule
from pdfem.scene.grains_file import read_grains_file
from pdfem.scene.placement import check_geometry, grain_arrays
from pdfem.scene.schedules import check_schedules
from pdfem.scene.values import SceneError, array_of_tables, check_table, join, show, table

_NAME = re.compile(S.NAME_PATTERN)


def resolve(doc, base_dir):
    """Check ``doc`` (a dict from TOML).

    Returns (resolved dict, grain arrays, material name -> id, grain label function).
    """
    # The effects register their tables when imported (pdfem.effects.register)
    import pdfem.effects  # noqa: F401

    doc = table(doc, "", "a TOML table")
    known = [sec.name for sec in S.all_sections()]
    for name in doc:
        if name not in known:
            raise SceneError(join("", name), f"unknown table (known: {', '.join(known)})")
    secs = {sec.name: sec for sec in S.all_sections()}
    for name, sec in secs.items():
        if sec.required and name not in doc:
            raise SceneError(name, f"required table [{name}] missing")
    r = {}
    # Plain tables
    for name in ("domain", "time", "element", "gravity", "damping", "bulk_viscosity"):
        if name in doc or name not in S.PRESENCE_TABLES:
            r[name] = check_table(doc.get(name, {}), secs[name].keys, name)
    _time_rules(r["time"])
    _element_rules(r["element"])
    _domain_rules(r["domain"])
    r["materials"] = _materials(doc["materials"])
    mat_ids = {name: i for i, name in enumerate(r["materials"])}
    # Bodies and conditions
    r["grains"] = [_named_material(check_table(g, S.GRAIN, f"grains[{i}]"), mat_ids,
                                   f"grains[{i}]")
                   for i, g in enumerate(array_of_tables(doc.get("grains", []), "grains"))]
    rows = None
    if "grains_file" in doc:
        gf = check_table(doc["grains_file"], S.GRAINS_FILE, "grains_file")
        if "material" in gf:
            _named_material(gf, mat_ids, "grains_file")
        rows = read_grains_file(gf, base_dir, mat_ids)
        gf["path"] = str(Path(base_dir, gf["path"]).resolve())
        r["grains_file"] = gf
    r["blocks"] = _blocks(doc.get("blocks", []), mat_ids)
    r["bc"] = _bcs(doc.get("bc", []), [b["name"] for b in r["blocks"]])
    # Contact and walls
    if "walls" in doc:
        r["walls"] = check_table(doc["walls"], S.WALLS, "walls")
        if r["walls"]["friction"] == 0.0 and "frictional" in r["walls"].values():
            raise SceneError("walls.friction", "must be > 0 when a wall is frictional")
    if "contact" in doc:
        r["contact"] = _contact(doc["contact"], mat_ids)
    # Heat and the effects that need it
    for name in ("heat",) + S.HEAT_EFFECTS:
        if name in doc:
            r[name] = check_table(doc[name], secs[name].keys, name)
    # The tables of registered effects: plain key tables (what each needs: _effect_rules)
    for sec in S.EFFECT_SECTIONS:
        if sec.name in doc:
            r[sec.name] = check_table(doc[sec.name], sec.keys, sec.name)
    if "thermal_bc" in doc:
        r["thermal_bc"] = [check_table(b, S.THERMAL_BC, f"thermal_bc[{i}]") for i, b in
                           enumerate(array_of_tables(doc["thermal_bc"], "thermal_bc"))]
    _effect_rules(r)
    if r["domain"]["periodic"] == "x":
        _periodic_rules(r)
    r["output"] = _output(doc.get("output", {}), r["time"]["end"], r)
    r["gauges"] = _gauges(doc.get("gauges", []), r["blocks"])
    if "shock" in doc:
        r["shock"] = _shock(doc["shock"], r)
    if "prepare" in doc:
        r["prepare"] = _prepare(doc["prepare"], r, mat_ids)
    r["guards"] = check_table(doc.get("guards", {}), S.GUARDS, "guards")
    if r["guards"]["cap_contact"] != "off" and "contact" not in r:
        raise SceneError("guards.cap_contact", "needs the [contact] table")
    r["run"] = check_table(doc.get("run", {}), S.RUN, "run")
    check_schedules(r, doc.get("output", {}))
    # Geometry at t=0
    if rows is not None and "nodes" in rows.arrays:
        if r["grains"]:
            raise SceneError("grains", "[[grains]] cannot be combined with a bed file in "
                             "grains_file")
        _bed_at_level(rows, r["element"])
    grains, label = grain_arrays(r["grains"], rows, mat_ids)
    check_geometry(r, grains, label)
    return r, grains, mat_ids, label


def _bed_at_level(rows, element):
    """A bed file meshed at level L0 serves any scene whose level is a multiple of L0: its
    grain meshes (and stored stresses and state, at the scene's rule) are subdivided in place
    (pdfem.prepare.relevel: the same polygons, finer quads), or re-meshed as rings."""
    from pdfem.prepare.relevel import (
        RULE_POINTS,
        refine_nodes,
        refine_points,
        ring_nodes,
        ring_points,
    )

    level, level0 = element["level"], rows.level
    if level % level0:
        raise SceneError("element.level", f"must be a multiple of {level0}, the level the bed "
                         f"file {rows.name} was meshed at (got {level})")
    ring = element["mesh"] == "ring"
    if level == level0 and not ring:
        return
    nodes, points = (ring_nodes, ring_points) if ring else (refine_nodes, refine_points)
    a = rows.arrays
    a["nodes"] = nodes(a["nodes"], level0, level)
    a["node_v"] = nodes(a["node_v"], level0, level)
    if "elem_sig" in a:
        nip = RULE_POINTS[element["rule"]]
        a["elem_sig"] = points(a["elem_sig"], level0, level, nip)
        a["elem_mst"] = points(a["elem_mst"], level0, level, nip)
    rows.level = level


def _time_rules(t):
    """dt_min below dt_max."""
    if t["dt_min"] >= t["dt_max"]:
        raise SceneError("time.dt_min", f"must be < time.dt_max = {show(t['dt_max'])} "
                         f"(got {show(t['dt_min'])})")


def _element_rules(el):
    """The coefficient of the hourglass spring is the coefficient stiffness's alone."""
    if el["hourglass_stiffness"] == "coefficient":
        el.setdefault("hourglass", 0.05)
    elif "hourglass" in el:
        raise SceneError("element.hourglass", 'only with hourglass_stiffness = "coefficient" '
                         '(the bending stiffness has no coefficient)')
    # Keep the schema's key order in the resolved table
    items = sorted(el.items(), key=lambda kv: list(S.ELEMENT).index(kv[0]))
    el.clear()
    el.update(items)


def _domain_rules(d):
    """rebalance: 0 or a ratio >= 1."""
    if 0.0 < d["rebalance"] < 1.0:
        raise SceneError("domain.rebalance", f"must be 0 (never) or >= 1 (max/mean load) "
                         f"(got {show(d['rebalance'])})")


def _periodic_rules(r):
    """Periodic sides in x: no side walls or conditions on them; each block spans the box in x
    with at least three elements (its left and right node columns become one), and no condition
    or held temperature on one of those columns alone."""
    x0, _, x1, _ = r["domain"]["box"]
    for side in ("left", "right"):
        if r.get("walls", {}).get(side, "none") != "none":
            raise SceneError(f"walls.{side}", 'must be "none" with domain.periodic = "x" (the '
                             "grains cross that side)")
    for i, bc in enumerate(r["bc"]):
        if bc.get("wall") in ("left", "right"):
            raise SceneError(f"bc[{i}].wall", f'no {bc["wall"]} wall with domain.periodic = '
                             '"x" (that side is the seam)')
        if bc.get("nodes") in ("left", "right"):
            raise SceneError(f"bc[{i}].nodes", f'{bc["nodes"]} nodes alone cannot be held with '
                             'domain.periodic = "x" (they are one column with the other side\'s)')
    for i, b in enumerate(r.get("thermal_bc", [])):
        if b["nodes"] in ("left", "right"):
            raise SceneError(f"thermal_bc[{i}].nodes", f'{b["nodes"]} nodes alone cannot be '
                             'held with domain.periodic = "x"')
    for i, b in enumerate(r["blocks"]):
        if b["box"][0] != x0 or b["box"][2] != x1:
            raise SceneError(f"blocks[{i}].box", f"must span the domain box in x, [{show(x0)}, "
                             f'{show(x1)}], with domain.periodic = "x" (got [{show(b["box"][0])}'
                             f', {show(b["box"][2])}])')
        if b["nx"] < 3:
            raise SceneError(f"blocks[{i}].nx", 'must be >= 3 with domain.periodic = "x" (got '
                             f'{b["nx"]}): two elements meet at one image only')


def _materials(value):
    """[materials.NAME] tables, each checked against its model's keys."""
    mats = table(value, "materials")
    if not mats:
        raise SceneError("materials", "at least one [materials.NAME] table is required")
    out = {}
    for name, tbl in mats.items():
        path = join("materials", name)
        if not _NAME.fullmatch(name):
            raise SceneError(path, f"bad material name (must match {S.NAME_PATTERN})")
        model = table(tbl, path).get("model", "elastic")
        # (a model that is not a string is reported by check_table: not hashable here)
        known = isinstance(model, str) and model in S.MATERIAL_MODELS
        keys = dict(S.MATERIAL_COMMON)
        if known:
            keys.update(S.MATERIAL_MODELS[model])
        hint = f' for model "{model}"' if known else ""
        m = check_table(tbl, keys, path, hint)
        _eos_rules(m, path)
        MODEL_RULES.get(m["model"], lambda m, p: None)(m, path)
        out[name] = m
    return out


def _eos_rules(m, path):
    """eos_s is given exactly when the Us-up equation of state is chosen; eos_gamma only
    with it, below 2 eos_s (the Mie-Gruneisen pressure then rises with compression at any
    energy)."""
    if m["eos"] == "us_up" and "eos_s" not in m:
        raise SceneError(f"{path}.eos_s", 'required with eos = "us_up"')
    if m["eos"] != "us_up" and "eos_s" in m:
        raise SceneError(f"{path}.eos_s", 'only with eos = "us_up" (got eos = '
                         f'"{m["eos"]}")')
    if m["eos_gamma"] != 0.0 and m["eos"] != "us_up":
        raise SceneError(f"{path}.eos_gamma", 'only with eos = "us_up" (got eos = '
                         f'"{m["eos"]}")')
    if m["eos"] == "us_up" and not m["eos_gamma"] < 2.0 * m["eos_s"]:
        raise SceneError(f"{path}.eos_gamma", f"must be < 2 eos_s = {show(2.0 * m['eos_s'])} "
                         f"(got {show(m['eos_gamma'])})")


def _cap_rules(m, path):
    """C < A; tension cut-off defaults to the envelope apex ln(A/C)/B."""
    why = strength_rule(m["A"], m["C"])
    if why:
        raise SceneError(f"{path}.C", why)
    if "tension_cutoff" not in m:
        m["tension_cutoff"] = envelope_apex(m["A"], m["B"], m["C"])
    # Keep the schema's key order in the resolved table
    order = list(S.MATERIAL_COMMON) + list(S.CAP)
    items = sorted(m.items(), key=lambda kv: order.index(kv[0]))
    m.clear()
    m.update(items)


# Model name -> rules tying its keys together (models without rules need no entry)
MODEL_RULES = {"cap": _cap_rules}


def _named_material(tbl, mat_ids, path):
    """Check that ``tbl["material"]`` names a [materials.NAME] table; returns ``tbl``."""
    if tbl["material"] not in mat_ids:
        raise SceneError(f"{path}.material", f"unknown material {show(tbl['material'])} "
                         f"(known: {', '.join(mat_ids)})")
    return tbl


def _blocks(value, mat_ids):
    """[[blocks]]: names valid and unique, materials known."""
    out = []
    for i, b in enumerate(array_of_tables(value, "blocks")):
        path = f"blocks[{i}]"
        blk = _named_material(check_table(b, S.BLOCK, path), mat_ids, path)
        if not _NAME.fullmatch(blk["name"]):
            raise SceneError(f"{path}.name", f"bad block name {show(blk['name'])} (must "
                             f"match {S.NAME_PATTERN})")
        for k, other in enumerate(out):
            if other["name"] == blk["name"]:
                raise SceneError(f"{path}.name", f"duplicate block name {show(blk['name'])} "
                                 f"(also blocks[{k}])")
        out.append(blk)
    return out


def _bcs(value, block_names):
    """[[bc]]: a body xor a wall; dof and velocity as the type requires."""
    out = []
    for i, b in enumerate(array_of_tables(value, "bc")):
        p = f"bc[{i}]"
        bc = check_table(b, S.BC, p)
        # Where: a block's nodes or a domain wall
        if ("body" in bc) == ("wall" in bc):
            raise SceneError(p, "give exactly one of body (a block name) or wall (a side)")
        if "body" in bc:
            _known_block(bc["body"], block_names, f"{p}.body")
            bc.setdefault("nodes", "all")
            side = bc["nodes"]
        elif "nodes" in bc:
            raise SceneError(f"{p}.nodes", "only with body (a wall condition takes every "
                             "node on the wall)")
        else:
            side = bc["wall"]
        # What: the constrained components and the prescribed velocity
        kind = bc["type"]
        if kind == "fixed":
            if bc.get("dof", "xy") != "xy":
                raise SceneError(f"{p}.dof", f'a fixed condition constrains "xy" (got '
                                 f"{show(bc['dof'])}); use type roller for one component")
            bc["dof"] = "xy"
        elif kind == "roller" and "dof" not in bc:
            if side == "all":
                raise SceneError(f"{p}.dof", 'required for a roller on nodes = "all"')
            bc["dof"] = "x" if side in ("left", "right") else "y"
        bc.setdefault("dof", "xy")
        if kind == "velocity" and "velocity" not in bc:
            raise SceneError(f"{p}.velocity", "required for type velocity")
        if kind != "velocity" and "velocity" in bc:
            raise SceneError(f"{p}.velocity", f"only for type velocity (this is {kind})")
        if "release" in bc and (kind != "velocity" or "body" not in bc):
            raise SceneError(f"{p}.release", "only for type velocity on a body")
        if bc["ramp_down"] > 0.0 and not bc["ramp_down"] <= bc.get("release", -1.0):
            raise SceneError(f"{p}.ramp_down", f"needs release >= ramp_down (got ramp_down "
                             f"{bc['ramp_down']!r}, release {bc.get('release', 'not given')})")
        out.append({k: bc[k] for k in S.BC if k in bc})
    return out


def _contact(value, mat_ids):
    """[contact] and its [contact.pairs."m1:m2"] overrides, fully filled in."""
    keys = dict(S.CONTACT, pairs=None)
    tbl = table(value, "contact")
    pairs_in = table(tbl.get("pairs", {}), "contact.pairs")
    c = check_table({k: v for k, v in tbl.items() if k != "pairs"},
                    {k: v for k, v in keys.items() if k != "pairs"}, "contact")
    ks_given = "ks" in c
    c.setdefault("ks", 0.5 * c["kn0"])
    c = {k: c[k] for k in S.CONTACT}
    pairs, seen = {}, {}
    for name, ptbl in pairs_in.items():
        path = join("contact.pairs", name)
        mats = name.split(":")
        if len(mats) != 2 or any(m not in mat_ids for m in mats):
            raise SceneError(path, f'expected "mat1:mat2" with known materials (known: '
                             f"{', '.join(mat_ids)})")
        key = tuple(sorted(mats))
        if key in seen:
            raise SceneError(path, f"same pair as contact.pairs.{seen[key]}")
        seen[key] = f'"{name}"'
        p = check_table(ptbl, S.CONTACT_PAIR, path)
        p.setdefault("kn0", c["kn0"])
        p.setdefault("delta_max", c["delta_max"])
        p.setdefault("ks", c["ks"] if ks_given else 0.5 * p["kn0"])
        p.setdefault("friction", c["friction"])
        p.setdefault("damping", c["damping"])
        pairs[name] = {k: p[k] for k in S.CONTACT_PAIR}
    c["pairs"] = pairs
    return c


# Why a table is needed, in the words of the error naming it
NEED_WHY = {"heat": " (the temperature field)",
            "thermal_expansion": ": thermo-elastic heating and thermal expansion are one "
                                 "coupling, and either alone creates energy (add the table)",
            "thermoelastic": ": thermo-elastic heating and thermal expansion are one "
                             "coupling, and either alone creates energy (add the table)"}


def _effect_rules(r):
    """Each present effect's requirements (pdfem.effects.base.Effect): the tables it needs,
    the keys every material must set and its own rules; one error naming the first miss.
    Then the thermal boundary conditions: [heat] and known blocks."""
    from pdfem.effects import REGISTRY

    for name, cls in REGISTRY.items():
        if not cls.present(r):
            continue
        for need in cls.requires:
            if need not in r:
                raise SceneError(name, f"needs the [{need}] table{NEED_WHY.get(need, '')}")
        for key in cls.material_keys:
            for mname, m in r["materials"].items():
                if key not in m:
                    raise SceneError(f"materials.{mname}.{key}", f"required by [{name}]")
        cls.check_scene(r)
    if "thermal_bc" in r:
        if "heat" not in r:
            raise SceneError("thermal_bc", "needs the [heat] table (the temperature field)")
        names = [b["name"] for b in r["blocks"]]
        for i, bc in enumerate(r["thermal_bc"]):
            _known_block(bc["body"], names, f"thermal_bc[{i}].body")


def _output(value, t_end, r):
    """[output]: derived intervals and fields; the output directory must be writable. The
    fields are the core frame fields and those the effects declare (Effect.frame_fields and
    Effect.outputs); by default the core ones and the defaults of the scene's effects (r: the
    tables resolved so far)."""
    from pdfem.effects import REGISTRY
    from pdfem.io.layout import CORE_FRAME

    o = check_table(value, S.OUTPUT, "output")
    owner = {n: cls for cls in REGISTRY.values() for n in (*cls.frame_fields, *cls.outputs)}
    if "fields" not in o:
        o["fields"] = ["x", "v", "stress"] + [n for cls in REGISTRY.values()
                                              if cls.frame_defaults and cls.present(r)
                                              for n in cls.frame_defaults]
    known = [n for n in CORE_FRAME if n != "stress_cell"] + list(owner)
    for i, name in enumerate(o["fields"]):
        if name not in known:
            raise SceneError(f"output.fields[{i}]", "must be each one of "
                             + ", ".join(f'"{n}"' for n in known) + f' (got "{name}")')
        cls = owner.get(name)
        if cls is not None and not cls.present(r):
            raise SceneError("output.fields", f'"{name}" needs {cls.needs}')
    if "x" not in o["fields"]:
        raise SceneError("output.fields", 'must list "x" (the node positions of every frame)')
    o.setdefault("interval", t_end / 20.0)
    o.setdefault("energy_interval", o["interval"] / 10.0)
    o.setdefault("gauge_interval", o["energy_interval"] / 10.0)
    parent = Path(o["path"]).parent
    if o["path"] == "" or Path(o["path"]).is_dir():
        raise SceneError("output.path", f"must name a file (got {show(o['path'])})")
    if not parent.is_dir() or not os.access(parent, os.W_OK | os.X_OK):
        raise SceneError("output.path", f"directory {show(str(parent))} does not exist or "
                         "is not writable")
    return {k: o[k] for k in S.OUTPUT}


def _known_block(name, names, path):
    """SceneError at ``path`` unless ``name`` is one of the block ``names``."""
    if name not in names:
        raise SceneError(path, f"unknown block {show(name)} (known: "
                         f"{', '.join(names) or 'no blocks'})")


def _gauges(value, blocks):
    """[[gauges]]: unique names; a block (whole, one side or one element) or a point."""
    out, names = [], [b["name"] for b in blocks]
    for i, g in enumerate(array_of_tables(value, "gauges")):
        p = f"gauges[{i}]"
        gauge = check_table(g, S.GAUGE, p)
        if not _NAME.fullmatch(gauge["name"]):
            raise SceneError(f"{p}.name", f"bad gauge name {show(gauge['name'])} (must match "
                             f"{S.NAME_PATTERN})")
        if any(o["name"] == gauge["name"] for o in out):
            raise SceneError(f"{p}.name", f"duplicate gauge name {show(gauge['name'])}")
        if ("body" in gauge) == ("point" in gauge):
            raise SceneError(p, "give exactly one of body (a block name) or point")
        if "body" in gauge:
            _known_block(gauge["body"], names, f"{p}.body")
            if "side" in gauge and "element" in gauge:
                raise SceneError(p, "give at most one of side and element")
            blk = blocks[names.index(gauge["body"])]
            if gauge.get("element", 0) >= blk["nx"] * blk["ny"]:
                raise SceneError(f"{p}.element", f"must be < {blk['nx'] * blk['ny']} (the "
                                 f"elements of block {blk['name']}) (got {gauge['element']})")
            if "element" not in gauge:
                gauge.setdefault("side", "all")
        else:
            for key in ("side", "element"):
                if key in gauge:
                    raise SceneError(f"{p}.{key}", "only with body (a point selects one "
                                     "element)")
        out.append({k: gauge[k] for k in S.GAUGE if k in gauge})
    return out


def crystal_hugoniot(material):
    """[c0, s] of the Hugoniot Us = c0 + s up that a material table with eos = "us_up"
    simulates (c0 = sqrt(bulk / density)); None for any other bulk response."""
    if material.get("eos") != "us_up":
        return None
    return [math.sqrt(material["bulk"] / material["density"]), material["eos_s"]]


def _crystal_hugoniot(sh, mat, materials):
    """shock.crystal_hugoniot: the grain material's own when it has an equation of state
    (then the key may not be typed again), else the key as given (or absent)."""
    own = crystal_hugoniot(materials[mat]) if mat is not None else None
    if own is None:
        return
    if "crystal_hugoniot" in sh:
        raise SceneError("shock.crystal_hugoniot", f"derived from materials.{mat} (eos = "
                         f"\"us_up\": [{own[0]:.6g}, {own[1]:.6g}]); remove the key")
    sh["crystal_hugoniot"] = own


def _shock(value, r):
    """[shock]: blocks and gauges that exist; the solid density and the crystal's Hugoniot."""
    sh = check_table(value, S.SHOCK, "shock")
    names = [b["name"] for b in r["blocks"]]
    for key in ("hammer", "anvil"):
        _known_block(sh[key], names, f"shock.{key}")
    gauges = [g["name"] for g in r["gauges"]]
    for key in ("hammer_gauge", "anvil_gauge"):
        if sh[key] not in gauges:
            raise SceneError(f"shock.{key}", f"unknown gauge {show(sh[key])} (known: "
                             f"{', '.join(gauges) or 'no gauges'})")
    mat = r.get("grains_file", {}).get("material") or (r["grains"][0]["material"]
                                                       if r["grains"] else None)
    if "solid_density" not in sh:
        if mat is None:
            raise SceneError("shock.solid_density", "required when no grain material is "
                             "named (grains_file.material or grains[0].material)")
        sh["solid_density"] = r["materials"][mat]["density"]
    _crystal_hugoniot(sh, mat, r["materials"])
    if not sh["precursor_fraction"] < sh["front_fraction"]:
        raise SceneError("shock.precursor_fraction", f"must be below front_fraction "
                         f"{sh['front_fraction']!r} (got {sh['precursor_fraction']!r})")
    return {k: sh[k] for k in S.SHOCK if k in sh}


def _prepare(value, r, mat_ids):
    """[prepare]: ranges ordered, material known; each method's own keys given."""
    pr = check_table(value, S.PREPARE, "prepare")
    if r["element"]["mesh"] != "kite":
        raise SceneError("element.mesh", "a bed is prepared on kite meshes, which its file "
                         "stores; a scene that runs it may re-mesh it as rings")
    for key in ("semi_axis", "aspect"):
        if pr[key][0] > pr[key][1]:
            raise SceneError(f"prepare.{key}", f"min must be <= max (got {pr[key]})")
    if pr["material"] not in mat_ids:
        raise SceneError("prepare.material", f"unknown material {show(pr['material'])} "
                         f"(known: {', '.join(mat_ids)})")
    need = {"rain": ("grains", "weight"), "geometric": ("packing", "height")}[pr["method"]]
    for key in need:
        if key not in pr:
            raise SceneError(f"prepare.{key}", f"required key missing (method "
                             f"\"{pr['method']}\")")
    if "weight" in pr:
        _known_block(pr["weight"], [b["name"] for b in r["blocks"]], "prepare.weight")
    if pr["method"] == "geometric" and r["domain"]["periodic"] != "none":
        raise SceneError("prepare.method", 'the geometric packing fills a box between side '
                         'walls: with domain.periodic = "x" use method = "rain", or pack '
                         "between walls and run the bed with periodic sides")
    return {k: pr[k] for k in S.PREPARE if k in pr}
