"""A prepared bed at another mesh level (and element rule): the same grains, finer quads.

A bed file holds every grain's mesh at one level ``L0`` (:mod:`pdfem.io.bedfile`).
:func:`relevel_bed` writes the same bed at level ``L`` (a multiple of ``L0``) without
re-preparing it: each kite of the deformed level-``L0`` mesh is a piecewise-bilinear map of
the unit square (s, t), and the level-``L`` node (kite i, s = j/L, t = k/L) is that map
evaluated there. So

- the grain keeps its polygon exactly (every level-``L0`` node is a level-``L`` node and the
  new boundary nodes lie on the old boundary edges): same area, same mass, no new overlaps;
- the node and element numbering is that of :func:`pdfem.mesh.ellipse.ellipse_mesh` at
  level ``L``, which the solver meshes before loading the bed's positions;
- velocities are interpolated the same way.

Stresses and material state (per element and integration point) go to the sub-elements of
each parent element. To a 2x2 rule: each sub-element integration point takes the values of
the parent's integration point whose quadrant of the parent (in natural coordinates) holds
it, so every stress keeps the state it was in equilibrium with (at ``L = L0`` this is the
identity). To a 1-point rule: every sub-element takes the parent's mean over its points.
From a 1-point bed every point takes the parent's single value.
"""

import h5py
import numpy as np

from pdfem.io.bedfile import COLUMNS, read_bed, write_bed
from pdfem.mesh.ellipse import _kite_numbering, ellipse_mesh
from pdfem.mesh.locate import locate, shape
from pdfem.mesh.ring import ring_mesh
from pdfem.scene.values import SceneError

# Natural coordinates of the 2x2 Gauss points, in the element kernel's order
_GP = 1.0 / np.sqrt(3.0)
_XI = np.array([-1.0, 1.0, 1.0, -1.0])
_ETA = np.array([-1.0, -1.0, 1.0, 1.0])
# Number of integration points of each rule
RULE_POINTS = {"1pt": 1, "2x2": 4}


def refine_nodes(nodes, level0, level):
    """Node values (n, nn0, d) of meshes at ``level0`` -> (n, nn, d) at ``level``.

    ``level`` must be a multiple of ``level0``. Each kite's values are interpolated
    bilinearly within the level-``level0`` cell that holds the new node.
    """
    if level % level0:
        raise ValueError(f"level {level} is not a multiple of the bed's level {level0}")
    idx0, idx = _kite_numbering(level0), _kite_numbering(level)
    n, d = nodes.shape[0], nodes.shape[2]
    out = np.zeros((n, 1 + 6 * level * (level + 1), d))
    # Parent cell and local coordinate of every s = j/L (t alike)
    u = np.arange(level + 1) * level0 / level
    c = np.minimum(np.floor(u).astype(np.int64), level0 - 1)
    w = u - c
    sw, tw = w[:, None, None], w[None, :, None]
    for i in range(6):
        q = idx0[i]
        p00, p10 = nodes[:, q[c[:, None], c[None, :]]], nodes[:, q[c[:, None] + 1, c[None, :]]]
        p11 = nodes[:, q[c[:, None] + 1, c[None, :] + 1]]
        p01 = nodes[:, q[c[:, None], c[None, :] + 1]]
        val = ((1 - sw) * (1 - tw) * p00 + sw * (1 - tw) * p10 + sw * tw * p11
               + (1 - sw) * tw * p01)
        # Kite i writes the nodes it owns (j >= 1); the centre from kite 0
        out[:, idx[i, 1:, :].ravel()] = val[:, 1:, :].reshape(n, -1, d)
        if i == 0:
            out[:, 0] = val[:, 0, 0]
    return out


def _quadrant(xi, eta):
    """The 2x2 point (kernel order) whose quadrant of the element holds natural (xi, eta)."""
    return np.where(eta < 0, np.where(xi < 0, 0, 1), np.where(xi < 0, 3, 2))


def refine_points(values, level0, level, nip):
    """Element point values (n, ne0, nip0, m) at ``level0`` -> (n, ne, nip, m) at ``level``
    with ``nip`` points per element (1 or 4; module docstring)."""
    r = level // level0
    n, _, nip0, m = values.shape
    # Parent element, and the sub-cell (a, b) within it, of every level-L element (i, j, k)
    i, j, k = np.meshgrid(np.arange(6), np.arange(level), np.arange(level), indexing="ij")
    parent = (i * level0 * level0 + (j // r) * level0 + (k // r)).ravel()
    a, b = (j % r).ravel(), (k % r).ravel()
    src = values[:, parent]
    if nip == 1:
        return src.mean(axis=2, keepdims=True)
    if nip0 == 1:
        return np.repeat(src, nip, axis=2)
    # Parent natural coordinates of each sub-element point -> the parent point of its quadrant
    xi = -1.0 + (2.0 * a[:, None] + 1.0 + _GP * _XI[None, :]) / r
    eta = -1.0 + (2.0 * b[:, None] + 1.0 + _GP * _ETA[None, :]) / r
    return np.take_along_axis(src, _quadrant(xi, eta)[None, :, :, None], axis=2)


def ring_nodes(nodes, level0, level):
    """Node values (n, nn0, d) of kite meshes at ``level0`` -> (n, nn, d) on the ring mesh of
    ``level`` (a multiple of ``level0``). The kite meshes are refined to ``level`` first
    (:func:`refine_nodes`); the ring's boundary nodes are that mesh's, in the same loop, and
    every other node is interpolated bilinearly in the kite element holding it in the
    unit-disc reference. So the grain keeps its polygon, exactly."""
    fine = refine_nodes(nodes, level0, level)
    ref_k, conn_k, bnd_k = ellipse_mesh(1.0, 1.0, level)
    ref, _, bnd = ring_mesh(1.0, 1.0, level)
    # Kite element and natural coordinates of every ring node, then the kite cells' maps
    elem, xi, eta = locate(ref_k, conn_k, ref)
    out = np.einsum("mk,nmkd->nmd", shape(xi, eta), fine[:, conn_k[elem]])
    out[:, bnd] = fine[:, bnd_k]
    return out


def ring_points(values, level0, level, nip):
    """Element point values (n, ne0, nip0, m) of kite meshes at ``level0`` -> (n, ne, nip, m)
    on the ring mesh of ``level``: refined to the kite mesh of ``level``
    (:func:`refine_points`), then each ring point takes the value of the kite point whose
    quadrant of the kite element holds it (that element's value for one point)."""
    fine = refine_points(values, level0, level, nip)
    ref_k, conn_k, _ = ellipse_mesh(1.0, 1.0, level)
    ref, conn, _ = ring_mesh(1.0, 1.0, level)
    # The ring's element points in the reference (element centres for one point)
    g = np.array([[-_GP, -_GP], [_GP, -_GP], [_GP, _GP], [-_GP, _GP]]) if nip == 4 \
        else np.zeros((1, 2))
    pts = np.einsum("pk,ekd->epd", shape(g[:, 0], g[:, 1]), ref[conn]).reshape(-1, 2)
    elem, xi, eta = locate(ref_k, conn_k, pts)
    quad = np.zeros(elem.shape, np.int64) if nip == 1 else _quadrant(xi, eta)
    val = fine[:, elem, quad]
    return val.reshape(values.shape[0], conn.shape[0], nip, values.shape[3])


def relevel_bed(src, dst, level, rule=None):
    """Write the bed file ``src`` as ``dst`` meshed at ``level`` (a multiple of its own).

    ``rule`` ("1pt" or "2x2") sets the integration points of the stored stresses and state;
    None keeps the bed's. Returns ``dst``. Raises :class:`~pdfem.scene.values.SceneError` for
    an unreadable bed or a level that is not a multiple of the bed's.
    """
    cols, nodes, vel, level0, stress, state = read_bed(src, str(src))
    if level < level0 or level % level0:
        raise SceneError("element.level", f"{level} is not a multiple of the level {level0} "
                         f"the bed file {src} was meshed at")
    with h5py.File(src, "r") as f:
        attrs = dict(f.attrs)
    attrs.update(level=int(level), relevelled_from=int(level0), relevelled_source=str(src))
    # Positions and velocities: the same polygons, subdivided
    x = refine_nodes(nodes, level0, level)
    v = refine_nodes(vel, level0, level)
    # Stresses and material state: each sub-element from its parent
    if stress is not None:
        nip = stress.shape[2] if rule is None else RULE_POINTS[rule]
        stress = refine_points(stress, level0, level, nip)
        state = refine_points(state, level0, level, nip)
    ell = np.stack([cols[c] for c in COLUMNS], axis=1)
    write_bed(str(dst), ell, x, v, attrs, stress, state)
    return dst
