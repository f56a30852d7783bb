"""The grain meshes a scene can choose (``element.mesh``): the report's kite mesh, or the
ring mesh whose boundary nodes all have two elements (:mod:`pdfem.mesh.ring`)."""

from pdfem.mesh.ellipse import ellipse_mesh
from pdfem.mesh.ring import ring_mesh

# element.mesh -> the function meshing an ellipse (a, b, level) -> (xy, conn, boundary)
MESHES = {"kite": ellipse_mesh, "ring": ring_mesh}


def grain_mesh(a, b, level, kind="kite"):
    """Mesh of an ellipse of semi-axes ``a``, ``b`` at ``level`` with the mesh ``kind``;
    ``(xy, conn, boundary)`` as :func:`pdfem.mesh.ellipse.ellipse_mesh` returns them."""
    return MESHES[kind](a, b, level)


def quads_per_grain(level, kind="kite"):
    """Elements of one grain: 6 n^2 (kite) or 6 n^2 + 12 n (ring) at level n."""
    return 6 * level * level + (12 * level if kind == "ring" else 0)
