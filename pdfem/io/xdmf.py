"""The XDMF sidecar of a run file: ParaView opens ``run.xdmf`` as a time series.

Each frame is a grid of quadrilaterals (``/mesh/conn``) whose points are that frame's slab
of ``/frames/x``; node fields (velocity, temperature, contact force) are point data and the
element fields cell data, one scalar per component (stress_xx, ..., kappa, ...), each a
hyperslab of its frame dataset. Element stresses come from ``/frames/stress_cell`` (the
element mean) when elements have several integration points.
"""

import os
from xml.sax.saxutils import quoteattr

import h5py

from pdfem.io.layout import frame_layout

# Components of the 4-vectors (stress, plastic strain) and 2-vectors
COMP4 = ("xx", "yy", "xy", "zz")
COMP2 = ("x", "y")


def _slab(fname, dset, shape, start, count, name):
    """A HyperSlab DataItem selecting ``count`` from ``start`` of dataset ``dset``."""
    dims = " ".join(str(n) for n in shape)
    sel = " ".join(str(n) for n in start) + "  " + " ".join("1" for _ in shape) + "  " + \
        " ".join(str(n) for n in count)
    out = [n for n in count if n != 1] or [1]
    return (f'<DataItem ItemType="HyperSlab" Dimensions="{" ".join(map(str, out))}" '
            f'Name={quoteattr(name)}>'
            f'<DataItem Dimensions="3 {len(shape)}" Format="XML">{sel}</DataItem>'
            f'<DataItem Dimensions="{dims}" NumberType="Float" Precision="8" Format="HDF">'
            f"{fname}:{dset}</DataItem></DataItem>")


def _attributes(f, fname, k):
    """Attribute elements of frame k: (name, center, dataset, component index or None)."""
    fr = f["frames"]
    out = []
    # Every frame field but the positions and the stresses (below), as the layout says
    for name, (per, _) in frame_layout().items():
        if name in ("x", "stress", "stress_cell") or name not in fr:
            continue
        center = "Node" if per == "node" else "Cell"
        shp = fr[name].shape
        if len(shp) == 2:
            out.append((name, center, name, shp, None, None))
        else:
            comps = COMP2 if shp[2] == 2 else COMP4
            out += [(f"{name}_{c}", center, name, shp, i, None) for i, c in enumerate(comps)]
    if "stress_cell" in fr:
        shp = fr["stress_cell"].shape
        out += [(f"stress_{c}", "Cell", "stress_cell", shp, i, None) for i, c in enumerate(COMP4)]
    elif "stress" in fr:
        shp = fr["stress"].shape
        out += [(f"stress_{c}", "Cell", "stress", shp, i, 0) for i, c in enumerate(COMP4)]
    xml = []
    for name, center, dset, shp, comp, ip in out:
        start = [k, 0] + ([ip] if ip is not None else []) + ([comp] if comp is not None else [])
        count = [1, shp[1]] + ([1] if ip is not None else []) + ([1] if comp is not None else [])
        xml.append(f'<Attribute Name="{name}" AttributeType="Scalar" Center="{center}">'
                   + _slab(fname, f"/frames/{dset}", shp, start, count, name) + "</Attribute>")
    return xml


def write_xdmf(h5_path, xdmf_path=None):
    """Write the sidecar of ``h5_path`` (default ``<stem>.xdmf`` next to it); return its path."""
    xdmf_path = xdmf_path or os.path.splitext(h5_path)[0] + ".xdmf"
    fname = os.path.relpath(h5_path, os.path.dirname(os.path.abspath(xdmf_path)) or ".")
    with h5py.File(h5_path, "r") as f:
        conn = f["mesh/conn"].shape
        times = f["frames/time"][...]
        xshape = f["frames/x"].shape
        grids = []
        for k, t in enumerate(times):
            geo = _slab(fname, "/frames/x", xshape, [k, 0, 0], [1, xshape[1], 2], "x")
            attrs = "".join(_attributes(f, fname, k))
            grids.append(
                f'<Grid Name="frame{k}" GridType="Uniform"><Time Value="{float(t)!r}"/>'
                f'<Topology TopologyType="Quadrilateral" NumberOfElements="{conn[0]}">'
                f'<DataItem Dimensions="{conn[0]} 4" NumberType="Int" Precision="8" '
                f'Format="HDF">{fname}:/mesh/conn</DataItem></Topology>'
                f'<Geometry GeometryType="XY">{geo}</Geometry>{attrs}</Grid>')
    text = ('<?xml version="1.0" ?>\n<Xdmf Version="3.0"><Domain>'
            '<Grid Name="pdfem" GridType="Collection" CollectionType="Temporal">\n'
            + "\n".join(grids) + "\n</Grid></Domain></Xdmf>\n")
    with open(xdmf_path + ".part", "w") as fh:
        fh.write(text)
    os.replace(xdmf_path + ".part", xdmf_path)
    return xdmf_path
