"""Set-up: the bodies of a run's first state, from a scene (and its bed) or from a checkpoint.

:func:`initial_bodies` meshes the grains a rank owns at t = 0 and every block, with the
boundary conditions, the material state (a prepared bed's stresses) and the lumped mass;
:func:`restart_bodies` reads a checkpoint's bodies and the cell owners of its grains. Both
return the store before the first rebuild: the stepper migrates the grains to their owners
and makes the ghosts (:meth:`pdfem.solver.Simulation.rebuild`).
"""

import tomllib

import numpy as np

from pdfem import build
from pdfem.boundary import BoundaryConditions
from pdfem.errors import InputError
from pdfem.kernels.element_1pt import hourglass_reference
from pdfem.kernels.element_measures import q4_lumped_mass
from pdfem.kernels.material import material_initial_state
from pdfem.parallel.owners import cell_owners, owned_cell_weights
from pdfem.store import NODE, Batch, Field, Store

# A restart's contact forces of the last step, carried with the nodes to their owners
RESTART_FC = Field("restart_contact_force", NODE, (2,), np.float64)


class Blocks:
    """The scene's blocks: global bodies, stored first on every rank and numbered after the
    grains (gids from ``first_gid``), each with its named node sets (block-local indices:
    all, bottom, top, left, right; pdfem.build.block_batch). The one way from a block's name
    and a node set to its nodes."""

    def __init__(self, names, sets, first_gid):
        self.names, self.sets, self.first_gid = names, sets, first_gid

    def __len__(self):
        return len(self.names)

    def index(self, name):
        """The block's position among the blocks, and in every rank's store."""
        return self.names.index(name)

    def gid(self, name):
        """The block's global body id."""
        return self.first_gid + self.index(name)

    def nodes(self, name, which="all"):
        """Block-local indices of the block's node set ``which``."""
        return self.sets[self.index(name)][which]


def initial_bodies(sim, scene, init_state):
    """(store, cell owners, :class:`Blocks`, the run's pdfem.boundary.BoundaryConditions): the
    grains this rank owns at t = 0 (by the partition of the grain centres' cells) and every
    block, meshed, with boundary conditions, material state and lumped mass;
    ``init_state(sim, store)``, when given, edits them."""
    comm, r = sim.comm, sim.resolved
    g = scene.grains
    ng = g["center"].shape[0]
    cells = sim.grid.cell_of(g["center"])
    weights = np.bincount(cells, minlength=sim.grid.ncell).astype(float)
    owner = cell_owners(r["domain"]["partition"], weights, sim.grid, comm.size)
    mine = np.nonzero(owner[cells] == comm.rank)[0]
    nst = sim.nst
    grains = build.grain_batch(sim.fields, sim.nip, nst, r["element"]["level"],
                               mine.astype(np.int64), g["center"][mine], g["axes"][mine],
                               g["angle"][mine], g["velocity"][mine], g["material"][mine],
                               r["element"]["mesh"])
    if "nodes" in g:
        # A prepared bed: the grain meshes as the preparation left them
        grains.a["x"] = g["nodes"][mine].reshape(-1, 2).copy()
        grains.a["v"] = g["node_v"][mine].reshape(-1, 2).copy()
    specs = r.get("blocks", [])
    bbatch, bsets = build.block_batch(sim.fields, sim.nip, nst, specs, ng, sim.mat_ids,
                                      sim.grid.periodic_x)
    blocks = Blocks([b["name"] for b in specs], bsets, ng)
    first = np.concatenate(([0], np.cumsum(bbatch.a["nn"])[:-1])).astype(np.int64)
    bcs = BoundaryConditions(r.get("bc", []), sim.box, blocks)
    bcs.set_on_blocks(bbatch, first)
    bcs.set_on_grains(grains)
    batch = Batch.concat(sim.fields, [bbatch, grains])
    material_initial_state(batch.a["mst"], batch.a["emat"], sim.mat_params)
    if "elem_sig" in g:
        bed_stress(batch, g, mine, int(bbatch.a["ne"].sum()))
    store = Store(sim.fields, batch, batch.nbody)
    q4_lumped_mass(store.x, store.conn, store.emat, sim.mat_params, 0, store.ne_own, store.m)
    if init_state is not None:
        init_state(sim, store)
    # The 1-point rule's hourglass modes are measured from this configuration
    if sim.nip == 1:
        hourglass_reference(store.x, store.conn, sim.hg_coef, 0, store.ne_own, store.hgref)
    return store, owner, blocks, bcs


def bed_stress(batch, g, mine, e0):
    """Stresses and material state of a prepared bed's grains (elements after e0)."""
    sig, mst = g["elem_sig"], g["elem_mst"]
    nip, nst = batch.a["sig"].shape[1], batch.a["mst"].shape[2]
    if sig.shape[2] != nip or mst.shape[3] != nst:
        raise InputError(f"grains_file: the bed file holds {sig.shape[2]} integration "
                         f"point(s) and {mst.shape[3]} state variable(s) per element; this "
                         f"scene has {nip} and {nst} (element.rule and the material models "
                         "must be the preparation's)")
    batch.a["sig"][e0:] = sig[mine].reshape(-1, nip, 4)
    batch.a["mst"][e0:] = mst[mine].reshape(-1, nip, nst)


def restart_bodies(sim, path):
    """(store, cell owners, checkpoint): every rank reads the global bodies and a block of
    grains of the checkpoint at ``path`` (its scene must be this run's); the cell owners
    partition the checkpoint's grains. The store carries the last step's contact forces
    (field RESTART_FC) when the checkpoint has them, so that they ride with the nodes."""
    from pdfem.io.checkpoint import read_checkpoint

    given = sim.scene.to_toml_string()
    ck = read_checkpoint(path, sim.fields, sim.comm,
                         lambda p, saved: same_scene(p, saved, given))
    fields = sim.fields + ([RESTART_FC] if ck.contact_force is not None else [])
    if ck.contact_force is not None:
        ck.batch.a[RESTART_FC.name] = ck.contact_force
    store = Store(fields, Batch(fields, ck.batch.a), ck.batch.nbody)
    # The partition of the checkpoint's grains: cell weights summed over the ranks
    weights = owned_cell_weights(sim.comm, store, sim.grid, sim.nglobal)
    owner = cell_owners(sim.resolved["domain"]["partition"], weights, sim.grid, sim.comm.size)
    return store, owner, ck


def drop_restart_forces(store, fields, ck):
    """After the first rebuild of a restart: the owned nodes' contact forces kept on the
    checkpoint (for the first frame), and the store without them."""
    if ck.contact_force is None:
        return store
    ck.contact_force = getattr(store, RESTART_FC.name)[: store.nn_own].copy()
    return Store(fields, Batch(fields, {f.name: getattr(store, f.name) for f in fields}),
                 store.nb_own)


def _new_defaults(saved, given):
    """Drop from the given scene the keys of [element] and of every material that the saved
    scene lacks and that hold the present schema's default: keys added since the checkpoint
    was written (element.mesh, a material's eos), which then meant that default."""
    from pdfem.scene import schema as S

    tables = [(saved.get("element", {}), given.get("element", {}), S.ELEMENT)]
    for name, mat in given.get("materials", {}).items():
        tables.append((saved.get("materials", {}).get(name, {}), mat, S.MATERIAL_COMMON))
    for old, new, keys in tables:
        for key in [k for k in new if k not in old and k in keys]:
            if new[key] == keys[key].default:
                del new[key]


def same_scene(path, saved, given):
    """A restart must run the checkpoint's scene; only [output], [guards] and the time keys
    end, safety, dt_min and max_steps may change."""
    a, b = tomllib.loads(saved), tomllib.loads(given)
    _new_defaults(a, b)
    for d in (a, b):
        d.pop("output", None)
        d.pop("guards", None)
        for key in ("end", "safety", "dt_min", "max_steps"):
            d.get("time", {}).pop(key, None)
    if a == b:
        return
    raise InputError(f"--restart: {path} was written for a different scene ({_difference(a, b)}; "
                     "only [output], [guards], time.end, safety, dt_min and max_steps may "
                     "change)")


def _difference(saved, given):
    """The first table of two scene dicts that differs, in words: one that only one of them
    has, or the first material (or other named sub-table) that differs."""
    for key in sorted(set(saved) | set(given)):
        a, b = saved.get(key), given.get(key)
        if a == b:
            continue
        if a is None or b is None:
            return f"[{key}] only in {'the checkpoint' if b is None else 'this scene'}"
        if key == "materials" and isinstance(a, dict) and isinstance(b, dict):
            for name in sorted(set(a) | set(b)):
                if a.get(name) != b.get(name):
                    if name not in a or name not in b:
                        where = "the checkpoint" if name not in b else "this scene"
                        return f"material {name} only in {where}"
                    return f"[materials.{name}] differs"
        return f"[{key}] differs"
    return "the scenes differ"
