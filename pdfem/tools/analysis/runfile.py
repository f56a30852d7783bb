"""Reading a shock run file (HDF5, serial h5py) into plain arrays.

The frames are reduced one at a time to what the front analysis needs (grain centroids and
velocities, hammer and anvil faces), so a long run is never held in memory whole; a single
frame's nodes, stresses and temperatures are read back on demand for the snapshot figures.
Grain centroids and velocities are means over a grain's nodes weighted by the lumped node
mass (each element gives a quarter of its frame-0 mass to each of its four nodes).
"""

import tomllib
from dataclasses import dataclass, field

import h5py
import numpy as np

from pdfem.errors import InputError
from pdfem.io.runcheck import check_run_file
from pdfem.mesh.quality import folded_area
from pdfem.scene.validate import crystal_hugoniot
from pdfem.tools.analysis.escape import contact_reach, escaped_mass

# Values of the [shock] keys when an older resolved scene lacks them
SHOCK_DEFAULTS = {"front_fraction": 0.5, "precursor_fraction": 0.05, "steady_tolerance": 0.1,
                  "plots": "png", "reference_us": 500.0, "reference_arrival": 8.0e-6,
                  "reference_density": 1240.0}


def element_areas(x, conn):
    """Areas (NE,) of the quads ``conn`` (NE, 4) with node positions ``x`` (NN, 2)."""
    xe, ye = x[conn, 0], x[conn, 1]
    # Shoelace formula over the four corners (counter-clockwise gives positive areas)
    return 0.5 * np.sum(xe * np.roll(ye, -1, axis=1) - np.roll(xe, -1, axis=1) * ye, axis=1)


def lumped_node_mass(elem_mass, conn, nn):
    """Lumped node masses (nn,): each element gives a quarter of its mass to each node."""
    return np.bincount(conn.ravel(), weights=np.repeat(elem_mass / 4.0, 4), minlength=nn)


def body_means(values, weights, node_body, nb):
    """Weighted means per body (nb,) of the node ``values`` (NN,); NaN for an empty body."""
    w = np.bincount(node_body, weights=weights, minlength=nb)
    s = np.bincount(node_body, weights=weights * values, minlength=nb)
    with np.errstate(invalid="ignore", divide="ignore"):
        return np.where(w > 0, s / np.where(w > 0, w, 1.0), np.nan)


@dataclass
class Run:
    """A run file's mesh, scene and per-frame reductions, as plain numpy arrays."""

    path: str
    scene: dict
    shock: dict
    width: float
    conn: np.ndarray
    node_body: np.ndarray
    elem_body: np.ndarray
    ng: int
    elem_mass: np.ndarray
    grain_mass: np.ndarray
    grain_diam: np.ndarray
    grain_material: str
    hammer_nodes: np.ndarray
    anvil_nodes: np.ndarray
    time: np.ndarray
    grain_y: np.ndarray
    grain_vy: np.ndarray
    hammer_y: np.ndarray
    hammer_vy: np.ndarray
    anvil_y: np.ndarray
    grain_top: np.ndarray
    grain_bottom: np.ndarray
    grain_xrange: np.ndarray
    escaped_mass: np.ndarray
    hammer_mean_vy: np.ndarray
    hammer_mass: float
    grain_top0: float
    gauge_time: np.ndarray
    gauges: dict
    drive: dict
    energy: dict
    has_stress: bool
    has_temperature: bool
    folded: np.ndarray
    notes: list = field(default_factory=list)

    def frame(self, k):
        """Frame k: node positions (NN, 2), element -sigma_yy (NE,) and temperature or None."""
        with h5py.File(self.path, "r") as f:
            fr = f["frames"]
            x = fr["x"][k]
            # Compressive stress: mean over the integration points, sign flipped
            syy = -fr["stress"][k][:, :, 1].mean(axis=1) if "stress" in fr else None
            temp = fr["temperature"][k][self.conn].mean(axis=1) if "temperature" in fr else None
        return x, syy, temp


def _shock_table(path, scene):
    """The [shock] table with defaults filled; InputError naming the file when absent."""
    if "shock" not in scene:
        raise InputError(f"{path}: no [shock] table in the run's scene")
    return {**SHOCK_DEFAULTS, **scene["shock"]}


def _block_rows(scene, ng, node_body, name, path):
    """(bottom row, top row, all) global node ids of block ``name`` meshed nx by ny."""
    names = [b["name"] for b in scene.get("blocks", [])]
    if name not in names:
        raise InputError(f"{path}: [shock] names block '{name}', not in the scene's blocks")
    k = names.index(name)
    nx = int(scene["blocks"][k]["nx"])
    nodes = np.flatnonzero(node_body == ng + k)
    # Block node (i, j) is i + (nx + 1) j: row 0 first, the top row last
    return nodes[: nx + 1], nodes[-(nx + 1):], nodes


def _finite(a, name, k, path):
    """Frame k of /frames/name, read as a; InputError unless every value is finite."""
    if not np.isfinite(a).all():
        raise InputError(f"{path}: /frames/{name}: frame {k} holds a non-finite value")
    return a


def _reduce_frames(fr, node_mass, node_body, ng, hammer, anvil, hall, gconn, gmass, reach, path):
    """Per frame: grain centroid y and v_y, hammer face y and v_y, anvil face y, the
    whole hammer's mass-weighted mean y and v_y, the highest and lowest grain node, the grain
    nodes' x range (nf, 2), the folded corners' area of the grain elements gconn over their
    area at frame 0, and the share of their mass gmass in elements with a node farther than
    ``reach`` past the anvil's or the hammer's face (pdfem.tools.analysis.escape)."""
    nf = fr["time"].shape[0]
    gy, gvy = np.zeros((nf, ng)), np.zeros((nf, ng))
    hy, hvy, ay, my, mvy, top, bottom, folded, lost = (np.zeros(nf) for _ in range(9))
    xrange = np.zeros((nf, 2))
    wh = node_mass[hall] / node_mass[hall].sum()
    gmask = node_body < ng
    nb_g, w = node_body[gmask], node_mass[gmask]
    has_v = "v" in fr
    # One frame at a time keeps the memory to one frame
    for k in range(nf):
        x = _finite(fr["x"][k], "x", k, path)
        gy[k] = body_means(x[gmask, 1], w, nb_g, ng)
        top[k], bottom[k] = x[gmask, 1].max(), x[gmask, 1].min()
        xrange[k] = x[gmask, 0].min(), x[gmask, 0].max()
        hy[k], ay[k], my[k] = x[hammer, 1].mean(), x[anvil, 1].mean(), wh @ x[hall, 1]
        folded[k] = folded_area(x, gconn).sum()
        lost[k] = escaped_mass(x[:, 1], gconn, gmass, ay[k] - reach, hy[k] + reach)
        if has_v:
            v = _finite(fr["v"][k], "v", k, path)
            gvy[k] = body_means(v[gmask, 1], w, nb_g, ng)
            hvy[k], mvy[k] = v[hammer, 1].mean(), wh @ v[hall, 1]
    t = fr["time"][:]
    # Without stored velocities, difference the positions
    if not has_v and nf > 1:
        gvy, hvy, mvy = np.gradient(gy, t, axis=0), np.gradient(hy, t), np.gradient(my, t)
    folded /= element_areas(fr["x"][0], gconn).sum()
    return t, gy, gvy, hy, hvy, ay, mvy, top, bottom, xrange, folded, lost


def _drive(scene, hammer):
    """The hammer's velocity condition, if any: driven (bool), release and ramp_down [s]."""
    for bc in scene.get("bc", []):
        if bc.get("body") == hammer and bc.get("type") == "velocity":
            return {"driven": True, "release": float(bc.get("release", np.inf)),
                    "ramp_down": float(bc.get("ramp_down", 0.0))}
    return {"driven": False, "release": np.inf, "ramp_down": 0.0}


def read_run(path):
    """Read the run file at ``path`` into a :class:`Run`; InputError when unreadable."""
    try:
        f = h5py.File(path, "r")
    except OSError as e:
        raise InputError(f"{path}: cannot read the run file ({e})") from None
    with f:
        try:
            text = f.attrs["scene"]
            if not isinstance(text, str):
                raise TypeError(f"a {type(text).__name__}, not TOML text")
            scene = tomllib.loads(text)
        except (KeyError, TypeError, OSError, RuntimeError, tomllib.TOMLDecodeError) as e:
            raise InputError(f"{path}: no readable scene attribute ({e})") from None
        shock = _shock_table(path, scene)
        # Every dataset read below: numeric, of the layout's shape, ids in range
        mats = scene.get("materials")
        check_run_file(f, path, series=True,
                       n_materials=len(mats) if isinstance(mats, dict) else None)
        try:
            return _read(f, path, scene, shock)
        except KeyError as e:
            raise InputError(f"{path}: missing dataset or key {e}") from None
        except (OSError, RuntimeError) as e:
            # A damaged block of the file (h5py's errors reading it)
            raise InputError(f"{path}: cannot read the run file ({e})") from None
        except (ValueError, IndexError, TypeError) as e:
            # A dataset of the wrong shape or kind: the file is not a complete run file
            msg = " ".join(str(e).split())
            raise InputError(f"{path}: not a complete run file ({type(e).__name__}: {msg})") \
                from None


def _read(f, path, scene, shock):
    """The body of :func:`read_run` on an open file."""
    m = f["mesh"]
    conn, node_body = m["conn"][:], m["node_body"][:]
    elem_body, elem_mat, kind = m["elem_body"][:], m["elem_material"][:], m["body_kind"][:]
    ng = int(np.sum(kind == 0))
    if ng == 0:
        raise InputError(f"{path}: the run has no grains")
    # Element and node masses from the frame-0 areas and the material densities
    mats = list(scene["materials"])
    dens = np.array([float(scene["materials"][n]["density"]) for n in mats])
    x0 = f["frames/x"][0]
    elem_mass = element_areas(x0, conn) * dens[elem_mat]
    node_mass = lumped_node_mass(elem_mass, conn, len(node_body))
    grain_mass = np.bincount(elem_body, weights=elem_mass, minlength=len(kind))[:ng]
    garea = np.bincount(elem_body, weights=element_areas(x0, conn), minlength=len(kind))[:ng]
    gmat = mats[int(np.bincount(elem_mat[elem_body < ng]).argmax())]
    shock.setdefault("solid_density", float(scene["materials"][gmat]["density"]))
    if "crystal_hugoniot" not in shock:
        shock["crystal_hugoniot"] = crystal_hugoniot(scene["materials"][gmat])
    hammer, _, hall = _block_rows(scene, ng, node_body, shock["hammer"], path)
    _, anvil, _ = _block_rows(scene, ng, node_body, shock["anvil"], path)
    gsel = elem_body < ng
    t, gy, gvy, hy, hvy, ay, mvy, top, bottom, xrange, folded, lost = _reduce_frames(
        f["frames"], node_mass, node_body, ng, hammer, anvil, hall, conn[gsel],
        elem_mass[gsel], contact_reach(scene), path)
    # Gauge series: every group under /gauges but the time axis
    gauges = {n: {"velocity": g["velocity"][:], "stress": g["stress"][:],
                  "force": g["force"][:] if "force" in g else None}
              for n, g in f["gauges"].items() if n != "time"}
    for key in ("hammer_gauge", "anvil_gauge"):
        if shock[key] not in gauges:
            raise InputError(f"{path}: [shock].{key} '{shock[key]}' is not a gauge of the run")
    energy = {n: d[:] for n, d in f["energy"].items()} if "energy" in f else {}
    box = scene["domain"]["box"]
    notes = [] if "v" in f["frames"] else ["velocities differenced from stored positions"]
    return Run(path=path, scene=scene, shock=shock, width=float(box[2] - box[0]), conn=conn,
               node_body=node_body, elem_body=elem_body, ng=ng, elem_mass=elem_mass,
               grain_mass=grain_mass, grain_diam=np.sqrt(4.0 * garea / np.pi),
               grain_material=gmat, hammer_nodes=hammer, anvil_nodes=anvil, time=t,
               grain_y=gy, grain_vy=gvy, hammer_y=hy, hammer_vy=hvy, anvil_y=ay, grain_top=top,
               grain_bottom=bottom, grain_xrange=xrange, escaped_mass=lost,
               hammer_mean_vy=mvy, hammer_mass=float(node_mass[hall].sum()),
               grain_top0=float(x0[node_body < ng, 1].max()), gauge_time=f["gauges/time"][:],
               gauges=gauges, drive=_drive(scene, shock["hammer"]), energy=energy,
               has_stress="stress" in f["frames"],
               has_temperature="temperature" in f["frames"], folded=folded, notes=notes)
