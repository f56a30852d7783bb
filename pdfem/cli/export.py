"""``pdfem export run.h5 --format vtu|xdmf|vtk|...``: frames of a run file through meshio.

vtu, vtk and any other single-mesh meshio format: one file per frame, ``<prefix>-NNNN.<ext>``
(points, quads, point data v/temperature/contact_force, cell data stress (element mean),
kappa, plastic_strain, element_temperature); xdmf: one meshio XDMF time series
(``<prefix>.xdmf`` + its ``.h5``). ``--frames`` picks all (default), ``last`` or a
comma-separated list of frame indices.
"""

import os

from pdfem.errors import InputError


def add_parser(sub):
    p = sub.add_parser("export", help="export the frames of a run file through meshio "
                       "(vtu, xdmf, vtk, ...)")
    p.add_argument("runfile", help="run file (HDF5)")
    p.add_argument("--format", default="vtu", help="meshio format: vtu (default), xdmf, vtk, "
                   "... (any meshio writer)")
    p.add_argument("-p", "--prefix", default=None, help="output prefix (default: the run "
                   "file without .h5)")
    p.add_argument("--frames", default="all", help="all (default), last, or indices 0,5,9")


def _frames(text, n):
    """Frame indices from --frames."""
    if text == "all":
        return list(range(n))
    if text == "last":
        return [n - 1] if n else []
    try:
        ks = [int(v) for v in text.split(",")]
    except ValueError:
        raise InputError(f"--frames: expected all, last or indices (got {text!r})") from None
    bad = [k for k in ks if not -n <= k < n]
    if bad:
        raise InputError(f"--frames: frame {bad[0]} out of range (the file has {n} frames)")
    return [k % n for k in ks]


def frame_mesh(f, k):
    """meshio.Mesh of frame k of an open run file."""
    import meshio
    import numpy as np

    fr = f["frames"]
    conn = f["mesh/conn"][...]
    point_data, cell_data = {}, {}
    for name in ("v", "temperature", "contact_force"):
        if name in fr:
            point_data[name] = fr[name][k]
    if "stress" in fr:
        sig = fr["stress_cell"][k] if "stress_cell" in fr else fr["stress"][k].mean(axis=1)
        cell_data["stress"] = [sig]
    for name in ("kappa", "plastic_strain", "element_temperature"):
        if name in fr:
            cell_data[name] = [fr[name][k]]
    cell_data["body"] = [f["mesh/elem_body"][...]]
    cell_data["material"] = [f["mesh/elem_material"][...].astype(np.int64)]
    # Points in 3-D (z = 0): what VTK formats store
    x = fr["x"][k]
    pts = np.concatenate([x, np.zeros((x.shape[0], 1))], axis=1)
    return meshio.Mesh(pts, [("quad", conn)], point_data=point_data, cell_data=cell_data)


def _components(data):
    """4-component element fields as scalars (meshio's XDMF knows 1, 2, 3, 6, 9 only)."""
    out = {}
    for name, arrs in data.items():
        a = arrs[0]
        if a.ndim == 2 and a.shape[1] == 4:
            for i, c in enumerate(("xx", "yy", "xy", "zz")):
                out[f"{name}_{c}"] = [a[:, i]]
        else:
            out[name] = arrs
    return out


def run(args):
    import h5py
    import meshio

    if not os.path.isfile(args.runfile):
        raise InputError(f"{args.runfile}: no such run file")
    prefix = args.prefix or os.path.splitext(args.runfile)[0]
    fmt = args.format.lower()
    try:
        f = h5py.File(args.runfile, "r")
    except OSError as exc:
        raise InputError(f"{args.runfile}: cannot read: {exc}") from None
    with f:
        if "frames" not in f or "mesh" not in f:
            raise InputError(f"{args.runfile}: not a pdfem run file (no /frames or /mesh)")
        times = f["frames/time"][...]
        ks = _frames(args.frames, times.shape[0])
        if fmt == "xdmf":
            # A meshio time series: one mesh, the frames as time steps
            m0 = frame_mesh(f, ks[0])
            with meshio.xdmf.TimeSeriesWriter(prefix + ".xdmf") as w:
                w.write_points_cells(m0.points, m0.cells)
                for k in ks:
                    m = frame_mesh(f, k)
                    w.write_data(float(times[k]), point_data=m.point_data,
                                 cell_data=_components(m.cell_data))
            print(f"pdfem export: {len(ks)} frame(s) -> {prefix}.xdmf")
            return 0
        ext = {"vtu": "vtu", "vtk": "vtk"}.get(fmt, fmt)
        for k in ks:
            path = f"{prefix}-{k:04d}.{ext}"
            try:
                meshio.write(path, frame_mesh(f, k), file_format=fmt)
            except (ValueError, KeyError) as exc:
                raise InputError(f"--format: meshio cannot write {fmt!r}: {exc}") from None
        print(f"pdfem export: {len(ks)} frame(s) -> {prefix}-NNNN.{ext}")
    return 0
