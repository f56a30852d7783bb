"""The hard cases of ``pdfem study hard``: scenes that push the solver where it breaks.

Each case is a function ``(folder, size) -> scene dict`` (tomllib form; SI units, stresses
tension positive) writing any file it needs (a bed file) into ``folder``. ``size`` is "ci"
(seconds, for the test suite) or "large" (the study). :data:`CASES` lists them with one line
each; :data:`LARGE_ONLY` are too long for the test suite. :data:`LADDERS` groups the speed
and refinement ladders, which run only when named (``--case speeds``), not with "all".
"""

import copy
import math
import os

import numpy as np

from pdfem.io.bedfile import write_bed
from pdfem.mesh.ellipse import ellipse_mesh, place
from pdfem.mesh.quality import jacobian_ratio
from pdfem.tools.study.speeds import packaged_doc, rung_doc, walls_doc

# The elastic grain of the non-shock cases (HMX-like moduli)
GRAIN = {"model": "elastic", "density": 1900.0, "bulk": 12.7e9, "shear": 4.4e9}
# Corner-Jacobian ratio (largest / smallest, per element) of the sheared meshes
SHEAR_RATIO = 10.0


def _shot(size, speed, end_ci, kn0_scale=1.0, end_large=None):
    """Shot 912 (small bed for ci, the packaged bed for large) with the report's grains (6
    fully integrated quads each) and the hammer a free steel plate (the scene's piston
    condition dropped) at ``speed``; large runs until the front has crossed the bed unless
    end_large is given."""
    doc = packaged_doc("small" if size == "ci" else "default")
    doc["element"] = {"rule": "2x2", "level": 1}
    hammer = doc["shock"]["hammer"]
    doc["bc"] = [b for b in doc["bc"] if b.get("body") != hammer]
    for b in doc["blocks"]:
        if "velocity" in b:
            b["velocity"] = [0.0, -float(speed)]
    # The front crosses the bed in about depth / (2 speed) at these speeds
    end = end_ci if size == "ci" else (end_large or doc["time"]["end"] * 288.0 / speed)
    doc["time"]["end"] = end
    doc["contact"]["kn0"] *= kn0_scale
    doc["output"] = {"path": "run.h5", "interval": end / 8, "energy_interval": end / 80}
    doc.pop("shock", None)
    doc.pop("gauges", None)
    return doc


def _fast(doc):
    """What a km/s impact needs: bulk viscosity in the grains, damped contacts (half of
    critical), so that boundary nodes do not bounce off the hammer at twice its speed."""
    doc["bulk_viscosity"] = {}
    doc["contact"]["damping"] = 0.5
    return doc


def hammer_1000(folder, size):
    """Shot 912 with the hammer at 1000 m/s (3.5 x the experiment)."""
    return _fast(_shot(size, 1000.0, 4.0e-7))


def hammer_2000(folder, size):
    """Shot 912 with the hammer at 2000 m/s."""
    return _fast(_shot(size, 2000.0, 3.0e-7))


def _piston(size, speed, level_large, level_ci=1, end_ci=1.0e-7, mesh="ring", eos=True,
            law="area"):
    """The small shot-912 bed's piston at ``speed`` (pdfem.tools.study.speeds.rung_doc:
    times scaled by 288/speed, the piston held until the slowest front has crossed): level_ci
    for end_ci at CI size, level_large to the scene's end for large, on ``mesh`` meshes; eos:
    the crystal on its Us-up Hugoniot (the packaged scene's), else a linear bulk modulus; law:
    the contact law."""
    doc = rung_doc(packaged_doc("small"), speed, "2x2",
                   level_ci if size == "ci" else level_large, mesh)
    if size == "ci":
        doc["time"]["end"] = end_ci
    end = doc["time"]["end"]
    if not eos:
        for key in ("eos", "eos_s"):
            doc["materials"]["hmx"].pop(key)
    doc["contact"]["law"] = law
    doc["output"] = {"path": "run.h5", "interval": end / 8, "energy_interval": end / 80}
    doc.pop("shock", None)
    doc.pop("gauges", None)
    return doc


def piston_1500_eos(folder, size):
    """The piston at 1500 m/s on ring meshes of level 2 (large), the crystal on its Hugoniot."""
    return _piston(size, 1500.0, 2)


def piston_2000_eos(folder, size):
    """The piston at 2000 m/s on ring meshes of level 1, the crystal on its Hugoniot."""
    return _piston(size, 2000.0, 1)


def piston_1500_potential(folder, size):
    """The piston at 1500 m/s on the scene's own kite meshes with the potential contact law:
    at CI size level 2 with the linear bulk between the side walls the packaged scene had,
    for 0.13 us (past the area law's stop at 0.119 us there, an element inside another; with
    periodic sides the linear bulk inverts a grain's tip at 0.104 us); level 3 to the scene's
    end for large, the crystal on its Hugoniot (with the linear bulk the crushed crystal
    inverts an element at 0.84 us)."""
    if size == "ci":
        return walls_doc(_piston(size, 1500.0, 3, level_ci=2, end_ci=1.3e-7, mesh="kite",
                                 eos=False, law="potential"))
    return _piston(size, 1500.0, 3, mesh="kite", eos=True, law="potential")


def _ladder(speed, level):
    """A rung of the ladders: the small bed's piston at ``speed`` on kite meshes of ``level``,
    the crystal on its Hugoniot, the potential contact law, to the scene's end (large only)."""
    def case(folder, size):
        return _piston(size, speed, level, mesh="kite", eos=True, law="potential")
    case.__doc__ = (f"The piston at {speed:g} m/s on kite meshes of level {level}, the crystal "
                    "on its Hugoniot, the potential contact law.")
    return case


# The ladders (large only, run by name): every speed at the scene's level 2, and the mesh
# levels at 1500 m/s
SPEEDS = (100.0, 288.0, 500.0, 1000.0, 1500.0, 2000.0)
LEVELS = (1, 2, 3, 4)
LADDER_CASES = {f"speed-{v:g}": (_ladder(v, 2), f"piston at {v:g} m/s, level 2, EOS, "
                                 "potential law") for v in SPEEDS}
LADDER_CASES.update({f"refine-1500-l{n}": (_ladder(1500.0, n), f"piston at 1500 m/s, level {n}, "
                                           "EOS, potential law") for n in LEVELS})
LADDERS = {"speeds": [f"speed-{v:g}" for v in SPEEDS],
           "refinement": [f"refine-1500-l{n}" for n in LEVELS]}


def stiff_contact(folder, size):
    """Shot 912 at 288 m/s with the contact stiffness kn0 100 x the scene's."""
    return _shot(size, 288.0, 3.0e-7, kn0_scale=100.0, end_large=6.0e-7)


def _chamber(width, height, grains, end, extra=None, mu=0.3, kn0=1.0e13):
    """A walled chamber of elastic grains under amplified gravity with damping."""
    doc = {
        "domain": {"box": [0.0, 0.0, width, height], "partition": "strips"},
        "time": {"end": end, "safety": 0.5},
        "gravity": {"g": [0.0, -1.0e6]},
        "damping": {"gamma": 2.0e4},
        "contact": {"kn0": kn0, "delta_max": 2.0e-5, "friction": mu},
        "walls": {"left": "frictionless", "right": "frictionless", "bottom": "frictional",
                  "friction": mu},
        "materials": {"grain": dict(GRAIN)},
        "grains": grains,
        "output": {"path": "run.h5", "interval": end / 8, "energy_interval": end / 80},
    }
    doc.update(extra or {})
    return doc


def _lattice(n, cols, pitch_x, pitch_y, a, b, seed):
    """n grains of semi-axes (a, b) on a lattice, random angles (reproducible)."""
    rng = np.random.default_rng(seed)
    out = []
    for i in range(n):
        cx = (i % cols + 0.5) * pitch_x
        cy = (i // cols + 0.5) * pitch_y
        out.append({"center": [cx, cy], "axes": [a, b], "angle": float(rng.uniform(0, np.pi)),
                    "material": "grain"})
    return out


def aspect_4(folder, size):
    """Needle-like grains (aspect ratio 4) falling into a chamber and piling up; a tip
    carrying a 20-grain pile needs kn0 = 1e14 to stay within delta_max."""
    n, cols = (12, 4) if size == "ci" else (400, 20)
    a, b = 4.0e-4, 1.0e-4
    pitch = 2.2 * a
    rows = math.ceil(n / cols)
    end = 6.0e-5 if size == "ci" else 4.0e-4
    return _chamber(cols * pitch, (rows + 1) * pitch, _lattice(n, cols, pitch, pitch, a, b, 4),
                    end, kn0=1.0e14)


def worst_ratio(xy, conn):
    """Largest over the elements of (largest / smallest corner Jacobian); inf if one <= 0."""
    r = jacobian_ratio(xy, conn).min()
    return 1.0 / r if r > 0.0 else math.inf


def sheared_mesh(a, b, level, ratio=SHEAR_RATIO):
    """An ellipse mesh whose interior nodes are pushed towards one side (a non-affine shear)
    until the worst element's corner-Jacobian ratio is ``ratio`` (bisection)."""
    xy, conn, bnd = ellipse_mesh(a, b, level)
    inner = np.setdiff1d(np.arange(xy.shape[0]), bnd)
    # Interior nodes move along +x by s (1 - r^2) b: most at the centre, none on the boundary
    r2 = (xy[inner, 0] / a) ** 2 + (xy[inner, 1] / b) ** 2
    lo, hi = 0.0, 1.0
    for _ in range(60):
        s = 0.5 * (lo + hi)
        test = xy.copy()
        test[inner, 0] += s * (1.0 - r2) * a
        if worst_ratio(test, conn) < ratio:
            lo = s
        else:
            hi = s
    out = xy.copy()
    out[inner, 0] += lo * (1.0 - r2) * a
    return out, conn


def sheared(folder, size):
    """Grains whose meshes are sheared to a corner-Jacobian ratio of 10, hit by a block at
    100 m/s on a fixed anvil."""
    cols, rows = (2, 2) if size == "ci" else (10, 6)
    a, b, level = 2.0e-4, 1.6e-4, 1
    xy, _ = sheared_mesh(a, b, level)
    pitch_x, pitch_y = 2.05 * a, 2.05 * b
    width, top = cols * pitch_x, 2.0e-4 + rows * pitch_y
    rng = np.random.default_rng(7)
    ell, nodes = [], []
    for i in range(cols * rows):
        c = ((i % cols + 0.5) * pitch_x, 2.0e-4 + (i // cols + 0.5) * pitch_y)
        ang = float(rng.choice([0.0, np.pi]))
        nodes.append(place(xy, c, ang))
        ell.append([c[0], c[1], a, b, ang])
    nodes = np.array(nodes)
    bed = os.path.abspath(os.path.join(folder, "sheared_bed.h5"))
    write_bed(bed, np.array(ell), nodes, np.zeros_like(nodes),
              {"level": level, "jacobian_ratio": SHEAR_RATIO})
    end = 1.5e-6 if size == "ci" else 4.0e-6
    return {
        "domain": {"box": [0.0, 0.0, width, top + 1.2e-4], "partition": "strips"},
        "time": {"end": end, "safety": 0.5},
        "element": {"rule": "2x2", "level": level},
        "contact": {"kn0": 1.0e15, "delta_max": 2.0e-5, "friction": 0.3},
        "walls": {"left": "frictionless", "right": "frictionless"},
        "materials": {"grain": dict(GRAIN), "steel": {"model": "elastic", "density": 7850.0,
                                                      "bulk": 160.0e9, "shear": 79.0e9}},
        "grains_file": {"path": bed, "material": "grain"},
        "blocks": [{"name": "anvil", "box": [0.0, 0.0, width, 2.0e-4], "material": "steel"},
                   {"name": "hammer", "box": [0.0, top + 2.0e-5, width, top + 1.2e-4],
                    "material": "steel", "velocity": [0.0, -100.0]}],
        "bc": [{"body": "anvil", "nodes": "bottom", "type": "fixed"},
               {"wall": "left", "type": "roller"}, {"wall": "right", "type": "roller"}],
        "output": {"path": "run.h5", "interval": end / 8, "energy_interval": end / 80},
    }


def fast_migration(folder, size):
    """Soft grains flying at 2-4 km/s both ways along a strip of small cells, so that every
    step moves them across several cells (and ranks); no contact, so nothing slows them."""
    n = 12 if size == "ci" else 600
    steps = 40 if size == "ci" else 200
    soft = {"model": "elastic", "density": 1000.0, "bulk": 1.0e6, "shear": 1.0e6}
    rng = np.random.default_rng(11)
    # Grains of semi-axes 4e-4 x 3e-4; stable step about L / c = 1.5e-4 / 48 m/s
    dt = 0.5 * 1.5e-4 / math.sqrt((1.0e6 + 4.0e6 / 3.0) / 1000.0)
    travel = 4000.0 * dt * steps
    width = 2.0 * travel + 0.02
    grains = []
    for i in range(n):
        sign = 1.0 if i % 2 == 0 else -1.0
        cx = width / 2 - sign * (travel / 2 + 0.002 * (i // 2 % 4))
        cy = 0.001 + 0.001 * (i % 6) + (0.006 * (i // 24))
        grains.append({"center": [cx, cy], "axes": [4.0e-4, 3.0e-4],
                       "angle": float(rng.uniform(0, np.pi)), "material": "grain",
                       "velocity": [sign * float(rng.uniform(2000.0, 4000.0)),
                                    float(rng.uniform(-20.0, 20.0))]})
    height = 0.001 + 0.006 * math.ceil(n / 24) + 0.001
    end = steps * dt
    return {
        "domain": {"box": [0.0, 0.0, width, height], "cell_size": 1.0e-3, "skin": 1.0e-4,
                   "partition": "strips"},
        "time": {"end": end, "safety": 1.0},
        "materials": {"grain": soft},
        "grains": grains,
        "output": {"path": "run.h5", "interval": end / 8, "energy_interval": end / 40},
    }


def squeeze_50(folder, size):
    """One cap (HMX) grain squeezed between two steel blocks to half its height at 20 m/s."""
    mats = packaged_doc("small")["materials"]
    r, gap = 1.0e-4, 2.0e-6
    level = 2 if size == "ci" else 4
    # Travel: the gap, half the height and what the blocks and contacts give elastically
    end = (gap + r + 6.0e-6) / 20.0
    return {
        "domain": {"box": [-4.0e-4, -1.5e-4, 4.0e-4, 2.5e-4]},
        "time": {"end": end, "safety": 0.5},
        "element": {"rule": "2x2", "level": level},
        "contact": {"kn0": 1.0e15, "delta_max": 2.0e-5, "friction": 0.3},
        "materials": copy.deepcopy(mats),
        "grains": [{"center": [0.0, 0.0], "axes": [r, r], "material": "hmx"}],
        "blocks": [{"name": "anvil", "box": [-4.0e-4, -1.5e-4, 4.0e-4, -r - gap],
                    "material": "steel", "ny": 2, "nx": 8},
                   {"name": "press", "box": [-4.0e-4, r + gap, 4.0e-4, 2.5e-4],
                    "material": "steel", "ny": 2, "nx": 8}],
        "bc": [{"body": "anvil", "nodes": "bottom", "type": "fixed"},
               {"body": "press", "type": "velocity", "velocity": [0.0, -20.0]}],
        "output": {"path": "run.h5", "interval": end / 8, "energy_interval": end / 80},
    }


def hot_conduction(folder, size):
    """Two cap grains colliding at 300 m/s with every heat effect on and a conductivity so
    high that conduction needs several sub-steps per mechanical step. The crystal keeps a
    linear bulk: thermal expansion and the thermo-elastic coupling need one."""
    mats = packaged_doc("small")["materials"]
    mats["hmx"]["conductivity"] = 2.0e5
    for key in ("eos", "eos_s"):
        mats["hmx"].pop(key, None)
    level = 2 if size == "ci" else 4
    end = 6.0e-7
    return {
        "domain": {"box": [0.0, 0.0, 8.0e-4, 4.0e-4]},
        "time": {"end": end, "safety": 0.5},
        "element": {"rule": "2x2", "level": level},
        "contact": {"kn0": 1.0e15, "delta_max": 2.0e-5, "friction": 0.3},
        "materials": {"hmx": mats["hmx"]},
        "grains": [{"center": [2.99e-4, 2.0e-4], "axes": [1.0e-4, 1.0e-4], "material": "hmx",
                    "velocity": [300.0, 0.0]},
                   {"center": [5.01e-4, 2.1e-4], "axes": [1.0e-4, 1.0e-4], "material": "hmx",
                    "velocity": [-300.0, 0.0]}],
        "heat": {}, "conduction": {}, "dissipation_heating": {}, "thermoelastic": {},
        "thermal_expansion": {}, "friction_heating": {}, "contact_conductance": {"h": 1.0e8},
        "output": {"path": "run.h5", "interval": end / 8, "energy_interval": end / 80},
    }


def settle_long(folder, size):
    """Grains settling in a chamber for 10^6 steps (large only)."""
    n, cols = 30, 6
    a = 2.0e-4
    pitch = 2.6 * a
    grains = _lattice(n, cols, pitch, pitch, a, 0.8 * a, 5)
    doc = _chamber(cols * pitch, (n // cols + 2) * pitch, grains, 1.0)
    doc["time"]["max_steps"] = 1_000_000
    doc["time"]["end"] = 1.0
    doc["output"] = {"path": "run.h5", "interval": 1.0e-3, "energy_interval": 1.0e-4}
    return doc


# name: (builder, what it stresses)
CASES = {
    "hammer-1000": (hammer_1000, "hammer at 1000 m/s into the shot 912 bed"),
    "hammer-2000": (hammer_2000, "hammer at 2000 m/s into the shot 912 bed"),
    "piston-1500-eos": (piston_1500_eos, "piston at 1500 m/s, ring meshes, crystal on its "
                        "Hugoniot"),
    "piston-2000-eos": (piston_2000_eos, "piston at 2000 m/s, ring meshes, crystal on its "
                        "Hugoniot"),
    "piston-1500-potential": (piston_1500_potential, "piston at 1500 m/s, kite meshes, the "
                              "potential contact law"),
    "stiff-contact": (stiff_contact, "contact stiffness kn0 x 100"),
    "aspect-4": (aspect_4, "grains of aspect ratio 4 piling up"),
    "sheared-mesh": (sheared, "grain meshes sheared to a Jacobian ratio of 10, hit at 100 m/s"),
    "fast-migration": (fast_migration, "grains crossing several cells (and ranks) per step"),
    "squeeze-50": (squeeze_50, "a grain squeezed to 50 % of its height between two blocks"),
    "hot-conduction": (hot_conduction, "heat with a conduction limit tighter than dt"),
    "settle-1e6": (settle_long, "10^6 steps of settling"),
}
CASES.update(LADDER_CASES)
LARGE_ONLY = ("settle-1e6",) + tuple(LADDER_CASES)
