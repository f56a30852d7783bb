"""Turn a scene into bodies: material table, grain and block meshes (their boundary
conditions: pdfem.boundary).

Global ids: grains are 0..ng-1 in scene order, blocks follow in scene order. Every rank
builds only the grains it owns at the start (and all blocks), so start-up is parallel too.
"""

import numpy as np

from pdfem.errors import InputError
from pdfem.kernels import params as P
from pdfem.kernels.cap import CAP_NST, cap_check_params
from pdfem.kernels.integrate import NACC
from pdfem.mesh.block import block_mesh
from pdfem.mesh.grain import grain_mesh
from pdfem.scene.cap import CAP_COLUMNS
from pdfem.store import Batch

# Scene names of the material models
MODELS = {"elastic": P.ELASTIC, "cap": P.CAP}


def material_table(materials):
    """(nmat, NPAR) parameter table from the resolved [materials] tables, in their order."""
    table = np.zeros((len(materials), P.NPAR))
    for i, tbl in enumerate(materials.values()):
        table[i, P.MODEL] = MODELS[tbl.get("model", "elastic")]
        table[i, P.RHO] = tbl["density"]
        table[i, P.BULK] = tbl["bulk"]
        table[i, P.SHEAR] = tbl["shear"]
        if tbl.get("eos") == "us_up":
            table[i, P.EOS_S] = tbl["eos_s"]
            table[i, P.EOS_G] = tbl.get("eos_gamma", 0.0)
        for key, col in CAP_COLUMNS.items():
            if key in tbl:
                table[i, col] = tbl[key]
    return table


def check_materials(materials, table):
    """Check model parameters the schema cannot; return the material state size per point:
    the cap's CAP_NST values where a material is a cap, then one more, the last, where a
    material has a Gruneisen coefficient (its points' internal energy, pdfem.kernels.eos)."""
    nst = 0
    for i, name in enumerate(materials):
        if int(table[i, P.MODEL]) == P.CAP:
            why = cap_check_params(table[i])
            if why:
                raise InputError(f"materials.{name}: {why}")
            nst = CAP_NST
    if np.any(table[:, P.EOS_G] > 0.0):
        nst += 1
    return nst


def boundary_flags(conn):
    """(ne, 4) int8: 1 where element edge k (node k -> k+1) belongs to no other element."""
    a = conn
    b = np.roll(conn, -1, axis=1)
    edges = np.sort(np.stack([a, b], axis=2).reshape(-1, 2), axis=1)
    _, inv, cnt = np.unique(edges, axis=0, return_inverse=True, return_counts=True)
    return (cnt[inv.ravel()] == 1).reshape(conn.shape).astype(np.int8)


def contact_lengths(x, conn, ebnd):
    """(ne,) each element's contact length L: its longest boundary edge (0 when it has none)."""
    edge = np.linalg.norm(x[np.roll(conn, -1, axis=1)] - x[conn], axis=2)
    return np.where(ebnd != 0, edge, 0.0).max(axis=1)


def _batch(fields, nip, nst, gid, nn, ne, isglobal, x, v, lconn, emat, ebnd):
    """A batch with zero stress and state and free nodes; the contact lengths of the elements
    as built (x, undeformed)."""
    nb, nnode, nelem = gid.shape[0], x.shape[0], lconn.shape[0]
    first = np.repeat(np.cumsum(nn) - nn, ne).astype(np.int64)
    arrays = {
        "gid": gid.astype(np.int64), "nn": nn.astype(np.int64), "ne": ne.astype(np.int64),
        "isglobal": np.full(nb, isglobal, np.int8), "acc": np.zeros((nb, NACC)),
        "x": x, "v": v, "m": np.zeros(nnode), "bcf": np.zeros((nnode, 2), np.int8),
        "bcv": np.zeros((nnode, 2)), "lconn": lconn.astype(np.int64),
        "emat": emat.astype(np.int32), "ebnd": ebnd.astype(np.int8),
        "elen": contact_lengths(x, lconn + first[:, None], ebnd),
        "sig": np.zeros((nelem, nip, 4)), "mst": np.zeros((nelem, nip, nst)),
        "ewint": np.zeros(nelem), "ewp": np.zeros(nelem),
        "hkey": np.zeros((0, 4), np.int64), "hval": np.zeros(0),
    }
    for f in fields:
        if f.name not in arrays:
            kind_n = {"body": nb, "node": nnode, "elem": nelem, "pair": 0}[f.kind]
            arrays[f.name] = np.zeros((kind_n,) + f.shape, f.dtype)
    return Batch(fields, arrays)


def grain_batch(fields, nip, nst, level, gids, center, axes, angle, velocity, mat, mesh="kite"):
    """Meshed elliptic grains (``mesh`` at ``level``: pdfem.mesh.grain), placed and rotated,
    as one batch."""
    ref, conn, _ = grain_mesh(1.0, 1.0, level, mesh)
    ng, nn, ne = gids.shape[0], ref.shape[0], conn.shape[0]
    # Scale the unit-disc mesh to each ellipse, rotate, translate
    loc = ref[None, :, :] * axes[:, None, :]
    c, s = np.cos(angle)[:, None], np.sin(angle)[:, None]
    x = np.empty((ng, nn, 2))
    x[:, :, 0] = c * loc[:, :, 0] - s * loc[:, :, 1] + center[:, 0:1]
    x[:, :, 1] = s * loc[:, :, 0] + c * loc[:, :, 1] + center[:, 1:2]
    v = np.repeat(velocity[:, None, :], nn, axis=1)
    lconn = np.tile(conn, (ng, 1))
    ebnd = np.tile(boundary_flags(conn), (ng, 1))
    emat = np.repeat(mat, ne)
    return _batch(fields, nip, nst, gids, np.full(ng, nn), np.full(ng, ne), 0,
                  x.reshape(-1, 2), v.reshape(-1, 2), lconn, emat, ebnd)


def block_batch(fields, nip, nst, blocks, gid0, mat_ids, periodic=False):
    """Rectangular blocks (global bodies) meshed nx by ny, in scene order. With periodic
    sides a block's left and right edges are a seam inside it, not a boundary (their node
    columns move as one: :func:`tied_nodes`)."""
    parts, sets = [], []
    for i, blk in enumerate(blocks):
        x0, y0, x1, y1 = blk["box"]
        nx = blk["nx"]
        xy, conn, _, node_sets = block_mesh(x0, y0, x1, y1, nx, blk["ny"])
        v = np.tile(np.asarray(blk["velocity"], float), (xy.shape[0], 1))
        emat = np.full(conn.shape[0], mat_ids[blk["material"]])
        ebnd = boundary_flags(conn)
        if periodic:
            # Edge 3 of the first column and edge 1 of the last are the seam
            ebnd[0::nx, 3] = 0
            ebnd[nx - 1::nx, 1] = 0
        parts.append(_batch(fields, nip, nst, np.array([gid0 + i]), np.array([xy.shape[0]]),
                            np.array([conn.shape[0]]), 1, xy, v, conn, emat, ebnd))
        sets.append(node_sets)
    return Batch.concat(fields, parts) if parts else Batch.empty(fields), sets


def joint_masses(m, partner):
    """The lumped masses m with each tied node's (partner >= 0, :func:`tied_nodes`) the sum of
    the pair's, lower index first: the mass the pair moves with (m itself without ties)."""
    tied = np.nonzero(partner >= 0)[0]
    if not tied.size:
        return m
    out = m.copy()
    lo, hi = np.minimum(tied, partner[tied]), np.maximum(tied, partner[tied])
    out[tied] = m[lo] + m[hi]
    return out


def tied_nodes(block_sets, first, nn):
    """Partner of each of the first nn nodes under periodic sides (int64, -1 = none): a
    block's left and right node columns, row by row (block i's nodes from first[i])."""
    partner = np.full(nn, -1, np.int64)
    for sets, f in zip(block_sets, first, strict=True):
        left, right = sets["left"] + f, sets["right"] + f
        partner[left], partner[right] = right, left
    return partner


class Layout:
    """Global numbering of bodies, nodes and elements (by gid), known to every rank."""

    def __init__(self, ngrain, level, blocks, mesh="kite"):
        _, conn, _ = grain_mesh(1.0, 1.0, level, mesh)
        gnn = int(conn.max()) + 1
        nn = np.array([gnn] * ngrain + [(b["nx"] + 1) * (b["ny"] + 1) for b in blocks],
                      np.int64)
        ne = np.array([conn.shape[0]] * ngrain + [b["nx"] * b["ny"] for b in blocks], np.int64)
        self.nbody = nn.shape[0]
        self.nn, self.ne = nn, ne
        self.node_start = np.concatenate(([0], np.cumsum(nn)[:-1])).astype(np.int64)
        self.elem_start = np.concatenate(([0], np.cumsum(ne)[:-1])).astype(np.int64)
        self.nnode, self.nelem = int(nn.sum()), int(ne.sum())
        self.kind = np.array([0] * ngrain + [1] * len(blocks), np.int8)
