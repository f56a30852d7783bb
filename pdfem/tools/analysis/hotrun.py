"""Reading a thermal run file for the hot-spot census: the mesh, element masses, and frame by
frame the node positions, element temperatures and cumulative heat by mechanism.

The element temperature is the frame field ``element_temperature`` or, without it, the mean
of the element's nodes' ``temperature`` (what the writer stores as element_temperature).
The heat by mechanism comes from the optional element frame fields ``heat_plastic``,
``heat_friction``, ``heat_thermoelastic`` and ``heat_conducted`` (J/m, cumulative since
t = 0), those present.
"""

import tomllib
from dataclasses import dataclass

import h5py
import numpy as np

from pdfem.errors import InputError
from pdfem.io.runcheck import check_run_file
from pdfem.tools.analysis.hotspots import MECHANISMS
from pdfem.tools.analysis.runfile import element_areas


@dataclass
class ThermalRun:
    """A run file's mesh and what the census reads of its frames."""

    path: str
    scene: dict
    conn: np.ndarray
    elem_body: np.ndarray
    body_kind: np.ndarray
    x0: np.ndarray
    elem_mass: np.ndarray
    time: np.ndarray
    temperature: str
    heat: tuple

    @property
    def grain(self):
        """(NE,) bool: the elements of grains (not of the blocks)."""
        return self.body_kind[self.elem_body] == 0

    def frames(self):
        """Yield (k, t, x (NN, 2), T (NE,), {mechanism: (NE,)}) frame by frame; InputError
        naming the frame where a value is not finite or a block cannot be read."""
        try:
            with h5py.File(self.path, "r") as f:
                fr = f["frames"]
                for k, t in enumerate(self.time):
                    x = _finite(fr["x"][k], "x", k, self.path)
                    if self.temperature == "element_temperature":
                        temp = fr["element_temperature"][k]
                    else:
                        temp = fr["temperature"][k][self.conn].mean(axis=1)
                    temp = _finite(temp, self.temperature, k, self.path)
                    heat = {m: _finite(fr[f"heat_{m}"][k], f"heat_{m}", k, self.path)
                            for m in self.heat}
                    yield k, float(t), x, temp, heat
        except (OSError, RuntimeError) as e:
            msg = " ".join(str(e).split())
            raise InputError(f"{self.path}: cannot read the run file ({msg})") from None


def _finite(a, name, k, path):
    """``a`` (frame k of /frames/name); InputError unless every value is finite."""
    if not np.isfinite(a).all():
        raise InputError(f"{path}: /frames/{name}: frame {k} holds a non-finite value")
    return a


def _scene(f, path):
    """The run's resolved scene; InputError when the attribute is missing or not TOML."""
    try:
        text = f.attrs["scene"]
        if not isinstance(text, str):
            raise TypeError(f"a {type(text).__name__}, not TOML text")
        return tomllib.loads(text)
    except (KeyError, TypeError, OSError, RuntimeError, tomllib.TOMLDecodeError) as e:
        raise InputError(f"{path}: no readable scene attribute ({e})") from None


def _densities(scene, path):
    """Densities of the scene's materials, in the order of their ids."""
    mats = scene.get("materials")
    if not isinstance(mats, dict) or not mats:
        raise InputError(f"{path}: the run's scene has no [materials]")
    out = []
    for name, m in mats.items():
        rho = m.get("density") if isinstance(m, dict) else None
        if isinstance(rho, bool) or not isinstance(rho, (int, float)) or not rho > 0:
            raise InputError(f"{path}: materials.{name}.density: missing or not positive in "
                             "the run's scene")
        out.append(float(rho))
    return np.array(out)


def _heat_fields(fr, path, nf, ne):
    """The mechanisms whose heat_<mechanism> frame field is present, each checked to hold
    floats of shape (F, NE)."""
    present = []
    for m in MECHANISMS:
        name = f"heat_{m}"
        if name not in fr:
            continue
        d = fr[name]
        if not isinstance(d, h5py.Dataset) or d.dtype.kind != "f" or d.shape != (nf, ne):
            shape = getattr(d, "shape", None)
            raise InputError(f"{path}: /frames/{name}: expected floats of shape ({nf}, {ne}) "
                             f"(frames by elements), got {shape}")
        present.append(m)
    return tuple(present)


def read_thermal_run(path):
    """The :class:`ThermalRun` of the file at ``path``; InputError (one line naming the file)
    when it is not a readable run file, holds no temperatures or no grains."""
    try:
        f = h5py.File(path, "r")
    except OSError as e:
        raise InputError(f"{path}: cannot read the run file ({e})") from None
    with f:
        scene = _scene(f, path)
        dens = _densities(scene, path)
        nf, _, ne = check_run_file(f, path, n_materials=len(dens))
        fr = f["frames"]
        temp = next((n for n in ("element_temperature", "temperature") if n in fr), None)
        if temp is None:
            raise InputError(f"{path}: no temperatures in the run file: add "
                             "\"element_temperature\" or \"temperature\" to output.fields, and "
                             "[heat] to the scene")
        if nf == 0:
            raise InputError(f"{path}: the run file holds no frames")
        heat = _heat_fields(fr, path, nf, ne)
        try:
            m = f["mesh"]
            conn, elem_body = m["conn"][:], m["elem_body"][:]
            kind, emat = m["body_kind"][:], m["elem_material"][:]
            x0 = _finite(fr["x"][0], "x", 0, path)
            time = fr["time"][:]
        except (OSError, RuntimeError) as e:
            msg = " ".join(str(e).split())
            raise InputError(f"{path}: cannot read the run file ({msg})") from None
    if not np.any(kind[elem_body] == 0):
        raise InputError(f"{path}: the run has no grain elements")
    # Mass from the frame-0 area: conserved while the element deforms
    mass = np.abs(element_areas(x0, conn)) * dens[emat]
    return ThermalRun(path=path, scene=scene, conn=conn, elem_body=elem_body, body_kind=kind,
                      x0=x0, elem_mass=mass, time=time, temperature=temp, heat=heat)
