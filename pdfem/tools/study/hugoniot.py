"""The bed's compaction Hugoniot and its static compression curve, as scenes derived from a
shock scene (``pdfem sweep``).

Shock points: the scene's hammer becomes a piston driven at a constant speed v until the
slowest steady compaction wave the bed allows has crossed it (a faster wave arrives earlier
and meets the anvil); no release. That slowest wave (:func:`slowest_front`) compacts the bed
fully to grains that are themselves compressed: by the most their material allows under the
wave's stress (their Hugoniot with an equation of state, sigma / K with a linear bulk, plus
the cap's W); with rigid grains it is the snowplow wave, Us = up / (1 - rho0/rho_s).

Static curve: the same bed compressed by the same piston slowly, with every density scaled
by ``scale`` (mass scaling: the static stress does not depend on mass, the stable step grows
by sqrt(scale)). A bed of disjoint grains resists only by inertia until it jams, and that
inertia is what mass scaling multiplies: the piston at speed v meets a snowplow stress
rho0 scale v^2 / (1 - phi0), the floor below which the curve is not static. The run prints
it; the piston's and the anvil's stresses agree where the compression is static.
"""

import copy
import math

import numpy as np

from pdfem.errors import InputError
from pdfem.mesh.ellipse import ellipse_mesh
from pdfem.prepare.packing import outlines, polygon_areas
from pdfem.tools.analysis.front import compacted_density

# Mass scale and piston speed of the static compression: a snowplow floor of
# 1235 x 100 x 4^2 / 0.35 = 5.6 MPa for the packaged bed
STATIC_SCALE, STATIC_SPEED = 100.0, 4.0
# Compaction the static run goes to beyond full density (1 - phi0)
STATIC_BEYOND = 0.03


def bed_figures(scene):
    """(H0, phi0, width) of a shock scene: bed height from the anvil face to the hammer face,
    packing as meshed grain area over width x H0."""
    r = scene.resolved
    sh = r["shock"]
    boxes = {b["name"]: b["box"] for b in r["blocks"]}
    H0 = boxes[sh["hammer"]][1] - boxes[sh["anvil"]][3]
    width = r["domain"]["box"][2] - r["domain"]["box"][0]
    g, level = scene.grains, r["element"]["level"]
    if "nodes" in g:
        area = float(polygon_areas(outlines(g["nodes"], level)).sum())
    else:
        # Meshed grains: the unit grain's polygon scaled by the semi-axes
        xy, _, bnd = ellipse_mesh(1.0, 1.0, level)
        unit = float(polygon_areas(xy[bnd][None])[0])
        area = unit * float(np.sum(g["axes"][:, 0] * g["axes"][:, 1]))
    return H0, area / (width * H0), width


def slowest_front(up, rho0, rho_s, material):
    """Slowest steady front at particle velocity up into a bed rho0 of grains rho_s of
    ``material``: full compaction to the densest bed its stress sigma = rho0 Us up allows
    (pdfem.tools.analysis.front.compacted_density: the grains' own bulk response, with an
    equation of state its Hugoniot, plus the cap's W); Us = up / (1 - rho0/rho1), solved by
    fixed point. NaN when no density the bed can hold carries the stress."""
    us = up / (1.0 - rho0 / rho_s)
    for _ in range(200):
        rho1 = compacted_density(rho0 * us * up, rho_s, material)
        if not rho1 > rho0:
            return math.nan
        new = up / (1.0 - rho0 / rho1)
        if abs(new - us) <= 1e-12 * us:
            break
        us = new
    return us


def grain_material(r):
    """The grain material's table of a resolved shock scene."""
    mat = r.get("grains_file", {}).get("material") or r["grains"][0]["material"]
    return r["materials"][mat]


def _piston(doc, hammer, speed):
    """The hammer of ``doc`` as a piston at ``speed`` (m/s, downward) to the end."""
    for blk in doc["blocks"]:
        if blk["name"] == hammer:
            blk["velocity"] = [0.0, -speed]
    bcs = [bc for bc in doc.get("bc", []) if not (bc.get("body") == hammer
                                                 and bc.get("type") == "velocity")]
    bcs.append({"body": hammer, "type": "velocity", "velocity": [0.0, -speed]})
    doc["bc"] = bcs


def shock_doc(doc, hammer, speed, H0, us_min):
    """Scene of one Hugoniot point: piston at ``speed`` until a front at ``us_min`` has
    crossed the bed, H0 / us_min."""
    d = copy.deepcopy(doc)
    _piston(d, hammer, speed)
    end = H0 / us_min
    d["time"] = dict(d["time"], end=end)
    d.setdefault("output", {}).update(interval=end / 40, energy_interval=end / 200,
                                      gauge_interval=end / 2000)
    d.setdefault("shock", {})["plots"] = "none"
    return d


def static_doc(doc, hammer, H0, phi0, scale=STATIC_SCALE, speed=STATIC_SPEED):
    """Scene of the static compression (see the module docstring) and its snowplow floor."""
    d = copy.deepcopy(doc)
    _piston(d, hammer, speed)
    for m in d["materials"].values():
        m["density"] = scale * m["density"]
    for key in ("bulk_viscosity", "damping", "shock", "gravity"):
        d.pop(key, None)
    end = H0 * (1.0 - phi0 + STATIC_BEYOND) / speed
    d["time"] = dict(d["time"], end=end)
    d["output"] = dict(d.get("output", {}), interval=end / 10, energy_interval=end / 200,
                       gauge_interval=end / 400)
    floor = phi0 * scale * speed ** 2 / (1.0 - phi0) * _solid_density(d, scale)
    return d, floor


def _solid_density(d, scale):
    """Grain density (unscaled) of a derived scene."""
    mat = d.get("grains_file", {}).get("material") or d["grains"][0]["material"]
    return d["materials"][mat]["density"] / scale


def static_curve(path, hammer_gauge, anvil_gauge, H0, rho0, width, speed, floor):
    """The stress-density curve of a static run file, per gauge sample: time, density
    rho0 H0 / (H0 - v t), the piston's and the anvil's stresses (their contact forces over the
    width, compressive positive); the kinetic energy gained over the work the piston has done
    at the end (how static the compression was), and the density from which on the piston's
    stress stays above twice the snowplow ``floor`` (the bed jams: below it the piston meets
    only the grains' inertia)."""
    import h5py

    with h5py.File(path, "r") as f:
        t = f["gauges/time"][:]
        piston = f[f"gauges/{hammer_gauge}/force"][:, 1] / width
        anvil = -f[f"gauges/{anvil_gauge}/force"][:, 1] / width
        e = {k: f[f"energy/{k}"][:] for k in ("time", "kinetic", "bc_work")}
    H = H0 - speed * t
    # Kinetic energy gained (the piston's own is constant) over the work, at the end
    gain, work = e["kinetic"][-1] - e["kinetic"][0], e["bc_work"][-1]
    dens = rho0 * H0 / H
    low = np.flatnonzero(piston <= 2.0 * floor)
    jam = low[-1] + 1 if low.size else 0
    return {"time": t, "density": dens, "sigma_piston": piston, "sigma_anvil": anvil,
            "kinetic_over_work": float(gain / work) if work > 0 else math.nan,
            "jamming_density": float(dens[jam]) if jam < dens.size else math.nan}


def check_scene(scene, path):
    """A shock scene the sweep can drive: InputError naming the file otherwise."""
    if "shock" not in scene.resolved:
        raise InputError(f"{path}: shock: sweep needs a scene with a [shock] table")
