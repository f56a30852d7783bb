"""Dense beds of elliptic grains for ``pdfem bench contact``.

Grains sit on a hexagonal lattice of pitch p = 2 r0 in a box with contact walls left, right and
bottom. Each grain's aspect b/a (in [0.7, 1]) and angle are drawn from a seeded rng; its major
semi-axis is then the largest that fits inside its lattice (Voronoi) hexagon, times a size factor
in [0.95, 1), so a is about 0.95..1.07 r0 and no two grains overlap at t=0 (the scene validator
accepts the bed). :func:`inflate_grains` gives the Simulation an ``init_state`` hook that scales
every grain about its centre node (by 12 % in pdfem bench contact) before the first rebuild:
neighbours whose extents nearly meet then overlap (mean overlap delta well below delta_max),
so about 3 of the 6 lattice neighbours of a grain touch it from the first step on, without
hundreds of settling steps. Soft contact (kn0 = 1e11 Pa/m) and damping keep that contact
set nearly constant over the few hundred steps of a benchmark.
"""

import math

import numpy as np

from pdfem.kernels.element_measures import q4_lumped_mass

# Face normals of a lattice hexagon (towards the six neighbours)
_PHI = np.arange(6) * (np.pi / 3.0)
# Relative margin that keeps every ellipse strictly inside its hexagon
_MARGIN = 1e-3


def hex_bed(n, r0=2.0e-4, seed=0):
    """Grain columns (x, y, a, b, angle) of an n-grain hexagonal bed and its box.

    Returns ``(cols, box)``: cols is a dict of (n,) float arrays, box = [x0, y0, x1, y1] with
    the lattice touching the left, right and bottom sides and two pitches of headroom above.
    """
    rng = np.random.default_rng(seed)
    p = 2.0 * r0
    ncol = max(1, round(math.sqrt(n)))
    nrow = -(-n // ncol)
    k = np.arange(n)
    row, col = k // ncol, k % ncol
    # Lattice centres; odd rows shifted by half a pitch
    x = (col + 0.5 + 0.5 * (row % 2)) * p
    y = (0.5 + row * math.sqrt(3.0) / 2.0) * p
    # Shapes: aspect and angle first, then the largest a that fits the hexagon
    q = rng.uniform(0.7, 1.0, n)
    angle = rng.uniform(0.0, np.pi, n)
    t = _PHI[None, :] - angle[:, None]
    support = np.sqrt(np.cos(t) ** 2 + (q[:, None] * np.sin(t)) ** 2).max(axis=1)
    # The bottom row also fits above the floor (a hexagon has a vertex, not a face, below)
    down = np.sqrt(np.sin(angle) ** 2 + (q * np.cos(angle)) ** 2)
    support = np.where(row == 0, np.maximum(support, down), support)
    a = rng.uniform(0.95, 1.0, n) * (1.0 - _MARGIN) * (0.5 * p) / support
    cols = {"x": x, "y": y, "a": a, "b": q * a, "angle": angle}
    box = [0.0, 0.0, (ncol + 0.5) * p, (nrow - 1) * p * math.sqrt(3.0) / 2.0 + 3.0 * p]
    return cols, box


# Grain materials of the benchmark beds: elastic HMX, or HMX with a crushable cap set
# (pressure-dependent envelope, cap within reach: the material kernel's dearer paths)
MATERIALS = {
    "elastic": 'model = "elastic"\ndensity = 1900.0\nbulk = 12.7e9\nshear = 4.4e9\n',
    "cap": ('model = "cap"\ndensity = 1900.0\nbulk = 12.7e9\nshear = 4.4e9\nA = 2.0e8\n'
            'B = 2.0e-9\nC = 1.5e8\nD = 5.0e-10\nR = 2.0\nW = 0.05\nkappa0 = -1.0e9\n'),
}


def bed_scene(n, folder, r0=2.0e-4, seed=0, inflate=1.12, level=1, kn0=1.0e11, gamma=1.0e5,
              g=-9.81, material="elastic", rule="1pt"):
    """Write ``bed.npz`` (columns x, y, a, b, angle) into ``folder``; return the scene TOML text.

    The scene has grains of ``material`` (a MATERIALS key; level ``level`` meshes, integration
    ``rule``), gravity g, damping gamma, the overlap contact (kn0, delta_max = 0.3 r0,
    friction 0.3) and frictionless side walls and a frictional floor. cell_size and skin are
    explicit and allow for grains grown by ``inflate``.
    """
    cols, box = hex_bed(n, r0, seed)
    np.savez(f"{folder}/bed.npz", **cols)
    skin = 0.2 * r0
    cell = 2.0 * inflate * float(cols["a"].max()) + skin
    return f"""
[domain]
box = {[float(v) for v in box]!r}
cell_size = {cell!r}
skin = {skin!r}

[time]
end = 1.0

[element]
level = {level}
rule = "{rule}"

[gravity]
g = [0.0, {g!r}]

[damping]
gamma = {gamma!r}

[materials.grain]
{MATERIALS[material]}
[contact]
kn0 = {kn0!r}
delta_max = {0.3 * r0!r}
friction = 0.3

[walls]
left = "frictionless"
right = "frictionless"
bottom = "frictional"
friction = 0.3

[grains_file]
path = "bed.npz"
material = "grain"

[output]
path = "bench.h5"
"""


def inflate_grains(factor):
    """An ``init_state(sim, store)`` hook: scale every grain about its centre node by factor.

    Grain meshes have their centre as node 0 (pdfem.mesh.ellipse). The lumped mass is
    recomputed on the grown meshes, so the density stays that of the scene.
    """

    def init_state(sim, store):
        # Grow each grain about its first (centre) node
        grain = store.isglobal[store.node_body] == 0
        centre = store.x[store.nstart[store.node_body]]
        store.x[grain] = centre[grain] + factor * (store.x[grain] - centre[grain])
        # Lumped mass of the grown meshes
        store.m[:] = 0.0
        q4_lumped_mass(store.x, store.conn, store.emat, sim.mat_params, 0, store.ne_own,
                       store.m)

    return init_state
