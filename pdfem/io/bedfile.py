"""Bed files: a prepared granular bed, the initial condition of an impact scene.

One HDF5 file written by ``python -m pdfem prepare`` (serially, by rank 0) and read by
``[grains_file]`` when its path ends in ``.h5``:

    /grains/x, y, a, b, angle (n,)   the grains as generated (x, y: centroid of the final nodes)
    /grains/nodes (n, nn, 2)        node positions of every grain mesh at the end [m]
    /grains/velocity (n, nn, 2)     node velocities: zero (the bed ends at rest)
    /grains/stress (n, ne, nip, 4)  Cauchy stress (xx, yy, xy, zz) of the final equilibrium [Pa]
    /grains/state (n, ne, nip, nst) material state (cap hardening), when the model has one
    attributes: level (grain mesh level), packing_fraction, bed_bottom, bed_top, width,
    grain_mass, seed, converged, scene (the preparation scene), pdfem_version, and the
    figures of each phase.

The last preparation phase brings the bed to rest under the impact scene's own materials
without body forces; its stresses and material state are stored so that the impact scene
starts in that equilibrium (it must use the same element rule and material models).
"""

import os

import h5py
import numpy as np

from pdfem import __version__
from pdfem.errors import SceneError

COLUMNS = ("x", "y", "a", "b", "angle")


def write_bed(path, ellipses, nodes, velocity, attrs, stress=None, state=None):
    """Write a bed file atomically (``path.part`` then rename); serial."""
    tmp = path + ".part"
    with h5py.File(tmp, "w") as f:
        g = f.create_group("grains")
        for k, name in enumerate(COLUMNS):
            g.create_dataset(name, data=ellipses[:, k])
        g.create_dataset("nodes", data=nodes)
        g.create_dataset("velocity", data=velocity)
        if stress is not None:
            g.create_dataset("stress", data=stress)
            g.create_dataset("state", data=state)
        for key, val in attrs.items():
            f.attrs[key] = val
        f.attrs["pdfem_version"] = __version__
    os.replace(tmp, path)


def read_bed(path, name):
    """Columns, node positions and velocities of a bed file; SceneError naming the file."""
    where = f"grains_file: {name}"
    try:
        with h5py.File(path, "r") as f:
            if "grains" not in f or "level" not in f.attrs:
                raise SceneError(where, "not a bed file written by `pdfem prepare` (no "
                                 "/grains group or level attribute)")
            g = f["grains"]
            missing = [c for c in COLUMNS + ("nodes", "velocity") if c not in g]
            if missing:
                raise SceneError(where, f"bed file lacks /grains/{missing[0]}")
            cols = {c: np.asarray(g[c][...], float) for c in COLUMNS}
            nodes = np.asarray(g["nodes"][...], float)
            vel = np.asarray(g["velocity"][...], float)
            level = int(f.attrs["level"])
            stress = np.asarray(g["stress"][...], float) if "stress" in g else None
            state = np.asarray(g["state"][...], float) if "state" in g else None
    except OSError as exc:
        raise SceneError("grains_file.path", f"cannot read {path}: {exc}") from None
    except (KeyError, ValueError, TypeError, AttributeError) as exc:
        # An entry of the wrong kind (a group for a dataset, strings for numbers)
        raise SceneError(where, f"not a complete bed file ({type(exc).__name__}: "
                         f"{' '.join(str(exc).split())})") from None
    n = cols["x"].shape[0]
    if nodes.ndim != 3 or nodes.shape[0] != n or nodes.shape[2] != 2 or vel.shape != nodes.shape:
        raise SceneError(where, f"/grains/nodes and /grains/velocity must have shape (n, nn, 2) "
                         f"with n = {n} (got {nodes.shape} and {vel.shape})")
    if not (np.all(np.isfinite(nodes)) and np.all(np.isfinite(vel))):
        raise SceneError(where, "non-finite node positions or velocities")
    if stress is not None and (stress.shape[0] != n or stress.ndim != 4 or state is None
                               or state.shape[:3] != stress.shape[:3]):
        raise SceneError(where, "/grains/stress and /grains/state must have shapes (n, ne, nip, "
                         "4) and (n, ne, nip, nst)")
    return cols, nodes, vel, level, stress, state
