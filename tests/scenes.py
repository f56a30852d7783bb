"""Small scenes built in code for the tests, as dicts (what ``tomllib`` makes of a file):
vary one by editing the dict, write it with ``write_scene`` or ``toml`` where a file is needed."""

import numpy as np


def elastic():
    """The elastic grain material (HMX-like constants) as a fresh dict."""
    return {"model": "elastic", "density": 1900.0, "bulk": 12.7e9, "shear": 4.4e9}


def _add(doc, extra):
    """Add the tables of ``extra`` (a dict) to the scene ``doc``; none may be there already."""
    for key, value in (extra or {}).items():
        assert key not in doc, f"{key}: already in the scene"
        doc[key] = value
    return doc


def drifting_grains(n=12, box=(0.0, 0.0, 0.024, 0.006), speed=200.0, end=4e-6, seed=1,
                    out="run.h5", level=1, rule="1pt", extra=None, frac=1.0):
    """Grains on a loose lattice drifting in random directions (no contact): migration.
    ``extra``: more tables (a dict) added to the scene."""
    rng = np.random.default_rng(seed)
    xmin, ymin, xmax, ymax = box
    cols = int(np.ceil(n / 2))
    grains = []
    for i in range(n):
        cx = xmin + (i % cols + 0.5) * frac * (xmax - xmin) / cols
        cy = ymin + (i // cols + 0.5) * (ymax - ymin) / 2
        ang = rng.uniform(0, np.pi)
        v = rng.uniform(-1, 1, 2) * speed
        v[0] = abs(v[0]) + speed
        grains.append({"center": [float(cx), float(cy)], "axes": [4.0e-4, 3.0e-4],
                       "angle": float(ang), "material": "grain",
                       "velocity": [float(v[0]), float(v[1])]})
    doc = {
        "domain": {"box": [xmin, ymin, xmax, ymax], "cell_size": 1.0e-3, "skin": 1.0e-4,
                   "partition": "strips"},
        "time": {"end": end, "safety": 0.5},
        "element": {"rule": rule, "level": level},
        "output": {"path": out, "interval": end / 4},
        "materials": {"grain": elastic()},
    }
    _add(doc, extra)
    doc["grains"] = grains
    return doc


def stretched_block(end=2e-6, out="run.h5", rule="1pt", nx=40, ny=2, v=1.0, extra=None):
    """A bar fixed on the left and pulled at velocity v on the right: a wave runs along.
    ``extra``: more tables (a dict) added to the scene."""
    doc = {
        "domain": {"box": [0.0, 0.0, 0.02, 0.001]},
        "time": {"end": end, "safety": 0.5},
        "element": {"rule": rule},
        "output": {"path": out, "interval": end / 4},
        "materials": {"grain": elastic()},
        "blocks": [{"name": "bar", "box": [0.0, 0.0, 0.02, 0.001], "nx": nx, "ny": ny,
                    "material": "grain"}],
        "bc": [{"body": "bar", "nodes": "left", "type": "fixed"},
               {"body": "bar", "nodes": "right", "type": "velocity", "dof": "x",
                "velocity": [v, 0.0]}],
    }
    return _add(doc, extra)


def collision(v=20.0, end=4e-6, kn0=1.0e16, dmax=2.0e-5, mu=0.0, rule="1pt", level=2,
              out="run.h5", extra=None, damping=0.0):
    """Two equal round grains flying at each other along x (frictionless unless mu > 0).
    ``extra``: more tables (a dict) added to the scene."""
    doc = {
        "domain": {"box": [0.0, 0.0, 0.004, 0.002], "cell_size": 1.0e-3, "skin": 5.0e-5},
        "time": {"end": end, "safety": 0.5},
        "element": {"rule": rule, "level": level},
        "contact": {"kn0": kn0, "delta_max": dmax, "friction": mu, "damping": damping},
        "output": {"path": out, "interval": end / 4, "energy_interval": end / 40},
        "materials": {"grain": elastic()},
        "grains": [{"center": [0.00155, 0.001], "axes": [4.0e-4, 4.0e-4], "material": "grain",
                    "velocity": [v, 0.0]},
                   {"center": [0.00245, 0.001], "axes": [4.0e-4, 4.0e-4], "material": "grain",
                    "velocity": [-v, 0.0]}],
    }
    return _add(doc, extra)


def fast_collision():
    """A 200 m/s collision at time.safety 1.0: energy error 0.34 % (0.15 % at time.safety 0.5,
    0.07 % at 0.25)."""
    doc = collision(v=200.0, kn0=1e13, dmax=4e-5, end=4e-6)
    doc["time"]["safety"] = 1.0
    return doc


def settling_bed(n=200, cols=20, r0=2.0e-4, seed=3, end=1e-4, g=-1.0e6, gamma=2.0e4, mu=0.3,
                 level=1, out="run.h5", partition="strips", extra=None):
    """n grains of random size and aspect on a loose lattice, falling onto the chamber floor
    between side walls (amplified gravity, damping, friction).
    ``extra``: more tables (a dict) added to the scene."""
    rng = np.random.default_rng(seed)
    pitch = 2.6 * r0
    width = cols * pitch
    rows = int(np.ceil(n / cols))
    height = (rows + 2) * pitch
    grains = []
    for i in range(n):
        cx = (i % cols + 0.5) * pitch + rng.uniform(-0.1, 0.1) * r0
        cy = (i // cols + 0.5) * pitch
        a = r0 * rng.uniform(0.9, 1.1)
        b = a * rng.uniform(0.7, 1.0)
        ang = float(rng.uniform(0, np.pi))
        grains.append({"center": [float(cx), float(cy)], "axes": [float(a), float(b)],
                       "angle": ang, "material": "grain"})
    doc = {
        "domain": {"box": [0.0, 0.0, width, height], "partition": partition},
        "time": {"end": end, "safety": 0.5},
        "element": {"level": level},
        "gravity": {"g": [0.0, g]},
        "damping": {"gamma": gamma},
        "contact": {"kn0": 1.0e13, "delta_max": 2.0e-5, "friction": mu},
        "walls": {"left": "frictionless", "right": "frictionless", "bottom": "frictional",
                  "friction": mu},
        "output": {"path": out, "interval": end / 4},
        "materials": {"grain": elastic()},
    }
    _add(doc, extra)
    doc["grains"] = grains
    return doc


def shock_materials():
    """The materials of the small shock scenes: HMX-like cap grains, steel-like cap blocks."""
    return {
        "hmx": {"model": "cap", "density": 1900.0, "bulk": 12.7e9, "shear": 4.4e9, "A": 2.0e8,
                "B": 2.0e-9, "C": 1.5e8, "D": 5.0e-10, "R": 2.0, "W": 0.05, "kappa0": -1.0e9},
        "steel": {"model": "cap", "density": 7850.0, "bulk": 160.0e9, "shear": 79.0e9,
                  "A": 1.0e9, "B": 1.0e-9, "C": 5.0e8, "D": 1.0e-10, "R": 2.0, "W": 0.001,
                  "kappa0": -5.0e9},
    }


def _chamber(doc, width):
    """Add the chamber of the small shock scenes: contact, side walls, the fixed bottom block
    (the blocks and bc arrays are started here)."""
    doc["contact"] = {"kn0": 1.0e16, "delta_max": 3.0e-5, "friction": 0.3}
    doc["walls"] = {"left": "frictionless", "right": "frictionless"}
    doc["blocks"] = [{"name": "bottom", "box": [0.0, 0.0, width, 2.0e-4],
                      "material": "steel"}]
    doc["bc"] = [{"body": "bottom", "nodes": "bottom", "type": "fixed"},
                 {"wall": "left", "type": "roller"}, {"wall": "right", "type": "roller"}]
    return doc


def prep_scene(grains=8, width=6.0e-4, height=4.0e-3, seed=7, out="bed.h5", phase_time=2.0e-3):
    """A small preparation scene: grains rained into a chamber `width` wide, a weight, relax
    (each phase of the preparation at most ``phase_time`` s)."""
    doc = {
        "domain": {"box": [0.0, 0.0, width, height], "partition": "strips"},
        "time": {"end": 1.0},
        "element": {"rule": "2x2"},
        "materials": shock_materials(),
    }
    _chamber(doc, width)
    doc["blocks"].append({"name": "weight", "box": [0.0, height - 3.0e-4, width, height],
                          "material": "steel"})
    doc["prepare"] = {
        "grains": grains, "seed": seed, "semi_axis": [1.0e-4, 1.3e-4], "aspect": [0.6, 1.0],
        "material": "hmx", "gravity": 5.0e5, "damping": 2.0e4, "stiffness_scale": 0.05,
        "contact_scale": 1.0e-3, "weight": "weight", "drop_gap": 1.0e-5,
        "ke_fraction": 1.0e-5, "phase_time": phase_time, "output": out}
    return doc


def shock_scene(bed, hammer_y0, width=6.0e-4, height=3.0e-3, end=6.0e-6, speed=288.0,
                out="shock.h5"):
    """A small hammer impact on a prepared bed, with the two gauges and the [shock] table."""
    doc = {
        "domain": {"box": [0.0, 0.0, width, height], "partition": "strips"},
        "time": {"end": end},
        "element": {"rule": "2x2"},
        "materials": shock_materials(),
    }
    _chamber(doc, width)
    doc["grains_file"] = {"path": bed, "material": "hmx"}
    doc["blocks"].append({"name": "hammer", "box": [0.0, hammer_y0, width, hammer_y0 + 3.0e-4],
                          "material": "steel", "velocity": [0.0, -speed]})
    doc["gauges"] = [{"name": "hammer", "body": "hammer", "side": "bottom"},
                     {"name": "bottom", "body": "bottom", "side": "top"}]
    doc["shock"] = {"hammer": "hammer", "anvil": "bottom", "hammer_gauge": "hammer",
                    "anvil_gauge": "bottom", "plots": "none"}
    doc["output"] = {"path": out, "interval": 5.0e-8, "energy_interval": 2.5e-8,
                     "gauge_interval": 1.0e-8}
    return doc


def periodic_press(shift=0.0, end=6.0e-7, out="press.h5", vx=150.0):
    """A strip with periodic sides, 1.2 mm wide: two rows of grains (some across the seam) on
    a fixed bottom block, pressed by a hammer that moves down and sideways (its friction drags
    the top grains across the seam). ``shift`` [m] moves the grains along x, their centres
    wrapped into the box: with a whole number of block elements (0.2 mm) the same periodic
    scene, cut at another place by the seam."""
    w, r = 1.2e-3, 1.1e-4
    grains = []
    for row in range(2):
        for col in range(4):
            cx = ((col + 0.1 + 0.5 * row) * w / 4 + shift) % w
            cy = 2.0e-4 + r + row * 2.05 * r
            grains.append({"center": [cx, cy], "axes": [r, 0.8 * r], "angle": 0.3 * (col + row),
                           "material": "hmx"})
    top = 2.0e-4 + 4.1 * r + 2.0e-5
    return {
        "domain": {"box": [0.0, 0.0, w, 1.4e-3], "partition": "strips", "periodic": "x"},
        "time": {"end": end},
        "element": {"rule": "2x2", "level": 2},
        "materials": shock_materials(),
        "contact": {"kn0": 1.0e16, "delta_max": 3.0e-5, "friction": 0.3, "law": "potential"},
        "bulk_viscosity": {},
        "blocks": [{"name": "bottom", "box": [0.0, 0.0, w, 2.0e-4], "nx": 6,
                    "material": "steel"},
                   {"name": "hammer", "box": [0.0, top, w, top + 2.0e-4], "nx": 6,
                    "material": "steel", "velocity": [vx, -300.0]}],
        "bc": [{"body": "bottom", "nodes": "bottom", "type": "fixed"}],
        "gauges": [{"name": "hammer", "body": "hammer", "side": "bottom"},
                   {"name": "bottom", "body": "bottom", "side": "top"}],
        "grains": grains,
        "output": {"path": out, "interval": end / 4, "energy_interval": end / 20,
                   "gauge_interval": end / 20},
    }


def checkpointed_grains():
    """Two grains, a checkpoint every few steps."""
    doc = drifting_grains(n=2, end=1e-7)
    doc["output"]["checkpoint_interval"] = 5e-8
    return doc


def inline_shock():
    """A small shock scene with two inline grains between hammer and anvil."""
    doc = shock_scene("none.h5", 1.0e-3, end=2e-7)
    del doc["grains_file"]
    doc["grains"] = [{"center": [1.5e-4, 3.5e-4], "axes": [1.0e-4, 1.0e-4], "material": "hmx"},
                     {"center": [4.5e-4, 3.5e-4], "axes": [1.0e-4, 1.0e-4], "material": "hmx"}]
    return doc


def every_field_shock():
    """inline_shock() with [heat] and every frame field the run file can hold (the core
    fields and those every built-in effect declares)."""
    from pdfem.effects import REGISTRY

    fields = ["x", "v", "stress"] + [n for cls in REGISTRY.values()
                                     for n in (*cls.frame_fields, *cls.outputs)]
    doc = inline_shock()
    doc["materials"]["hmx"]["specific_heat"] = 1444.0
    doc["materials"]["steel"]["specific_heat"] = 450.0
    doc["output"]["fields"] = fields
    doc["heat"] = {}
    return doc


def packaged(name):
    """A packaged scene (pdfem/scenes) as a dict, its bed path made absolute."""
    import tomllib
    from importlib import resources

    path = resources.files("pdfem") / "scenes" / name
    with open(path, "rb") as f:
        doc = tomllib.load(f)
    if "grains_file" in doc:
        doc["grains_file"]["path"] = str(path.parent / doc["grains_file"]["path"])
    return doc


def toml(doc):
    """The TOML text of a scene dict (the scene loader reads it back to the same dict)."""
    from pdfem.scene.toml_out import dumps

    return dumps(doc)


def write_scene(path, doc):
    """Write a scene dict as TOML (the scene loader reads it back); return the path."""
    from pdfem.scene.toml_out import dumps

    path.write_text(dumps(doc))
    return path


def small_prepare(out="bed.h5", **prepare):
    """The packaged small geometric preparation (1 mm x 2 mm at 0.65), [prepare] overridden."""
    doc = packaged("shot912_small_prepare.toml")
    doc["prepare"].update(output=out, **prepare)
    return doc


def small_shock(bed, out="shock.h5", plots="none"):
    """The packaged small piston shot on the bed file ``bed``."""
    doc = packaged("shot912_small.toml")
    doc["grains_file"]["path"] = str(bed)
    doc["output"]["path"] = out
    doc["shock"]["plots"] = plots
    return doc


def crystal_column(up, out="c.h5", height=3.0e-3, ny=300, c0=2770.0, s=2.29, rule="1pt",
                   eos=True):
    """A column of crystal (HMX's density, Us = c0 + s up) in uniaxial strain: the bottom
    fixed, every node held in x, the top nodes driven down at ``up`` from t = 0 against
    material at rest, with bulk viscosity; shear modulus a thousandth of the bulk (a fluid
    to the Hugoniot's accuracy). Runs for 0.8 of the time the shock needs to cross it."""
    rho = 1900.0
    k0 = rho * c0 * c0
    width = 1.0e-4
    end = 0.8 * height / (c0 + s * up)
    hmx = {"model": "elastic", "density": rho, "bulk": k0, "shear": 1.0e-3 * k0}
    if eos:
        hmx.update(eos="us_up", eos_s=s)
    return {
        "domain": {"box": [0.0, 0.0, width, height]},
        "time": {"end": end, "safety": 0.5},
        "element": {"rule": rule},
        "bulk_viscosity": {},
        "materials": {"hmx": hmx},
        "blocks": [{"name": "col", "box": [0.0, 0.0, width, height], "nx": 1, "ny": ny,
                    "material": "hmx"}],
        "bc": [{"body": "col", "nodes": "bottom", "type": "fixed"},
               {"body": "col", "nodes": "top", "type": "velocity", "velocity": [0.0, -up]},
               {"body": "col", "nodes": "all", "type": "velocity", "dof": "x",
                "velocity": [0.0, 0.0]}],
        "output": {"path": out, "interval": end / 80, "energy_interval": end / 80},
    }
