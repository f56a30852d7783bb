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
    p.add_argument("--force", action="store_true", help="overwrite existing output files")


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
    # A frame given twice (0,0 or 1,-1 of two frames) is written once
    return list(dict.fromkeys(k % n for k in ks))


def frame_mesh(f, k):
    """meshio.Mesh of frame k of an open run file; InputError where its blocks are damaged."""
    try:
        return _frame_mesh(f, k)
    except (OSError, RuntimeError) as exc:
        # h5py raises OSError or RuntimeError reading a damaged block
        msg = " ".join(str(exc).split())
        raise InputError(f"{f.filename}: cannot read frame {k} of the run file ({msg})") \
            from None


def _frame_mesh(f, k):
    """The body of :func:`frame_mesh`."""
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


def _format(fmt):
    """A meshio writer's name, or InputError listing them."""
    import meshio

    known = sorted({f for fs in meshio.extension_to_filetypes.values() for f in fs})
    if fmt not in known:
        raise InputError(f"--format: meshio has no writer {fmt!r} (known: {', '.join(known)})")
    return fmt


def _outputs(runfile, prefix, fmt, ks, force):
    """The files of the export (checked: new or --force, never the run file itself)."""
    from pdfem.cli.paths import check_output_path

    if fmt == "xdmf":
        # meshio's XDMF time series: <prefix>.xdmf and its data in <prefix>.h5
        paths = [prefix + ".xdmf", prefix + ".h5"]
    else:
        ext = {"vtu": "vtu", "vtk": "vtk"}.get(fmt, fmt)
        paths = [f"{prefix}-{k:04d}.{ext}" for k in ks]
    for path in paths:
        check_output_path(path, force, "--prefix")
        if os.path.exists(path) and os.path.samefile(path, runfile):
            raise InputError(f"--prefix: {path} is the run file being exported; give another "
                             "--prefix")
    return paths


def _write_xdmf(f, times, ks, paths):
    """The XDMF time series, written in a scratch folder beside its final place (meshio puts
    the .h5 in the working directory) and moved there when complete."""
    import contextlib
    import tempfile

    import meshio

    folder = os.path.dirname(os.path.abspath(paths[0]))
    stem = os.path.splitext(os.path.basename(paths[0]))[0]
    with tempfile.TemporaryDirectory(dir=folder, prefix=".pdfem-export-") as tmp:
        with contextlib.chdir(tmp):
            m0 = frame_mesh(f, ks[0])
            with meshio.xdmf.TimeSeriesWriter(stem + ".xdmf") as w:
                w.write_points_cells(m0.points, m0.cells)
                for k in ks:
                    m = frame_mesh(f, k)
                    w.write_data(float(times[k]), point_data=m.point_data,
                                 cell_data=_components(m.cell_data))
        for ext, path in zip((".xdmf", ".h5"), paths, strict=True):
            os.replace(os.path.join(tmp, stem + ext), path)


def _write_frames(f, fmt, ks, paths):
    """One file per frame, each written as ``<path>.part``; renamed when all are complete."""
    import meshio

    tmps, done = [p + ".part" for p in paths], False
    try:
        for k, tmp in zip(ks, tmps, strict=True):
            mesh = frame_mesh(f, k)
            try:
                meshio.write(tmp, mesh, file_format=fmt)
            except (ValueError, KeyError, TypeError, meshio.WriteError) as exc:
                raise InputError(f"--format: meshio cannot write {fmt!r}: {exc}") from None
        done = True
    finally:
        for tmp in tmps:
            if not done and os.path.exists(tmp):
                os.remove(tmp)
    for tmp, path in zip(tmps, paths, strict=True):
        os.replace(tmp, path)


def run(args):
    import h5py

    from pdfem.io.probe import check_metadata
    from pdfem.io.runcheck import check_run_file

    if not args.runfile:
        raise InputError("runfile: empty file name")
    if not os.path.isfile(args.runfile):
        raise InputError(f"{args.runfile}: no such run file")
    prefix = os.path.splitext(args.runfile)[0] if args.prefix is None else args.prefix
    fmt = _format(args.format.lower())
    # Damaged metadata can hang the HDF5 library: read it in a child process first
    check_metadata(args.runfile)
    try:
        f = h5py.File(args.runfile, "r")
    except OSError as exc:
        raise InputError(f"{args.runfile}: cannot read: {exc}") from None
    with f:
        # Every dataset the export reads: numeric, of the layout's shape, ids in range
        check_run_file(f, args.runfile)
        try:
            times = f["frames/time"][...]
        except (OSError, RuntimeError) as exc:
            raise InputError(f"{args.runfile}: /frames/time: cannot read ({exc})") from None
        ks = _frames(args.frames, times.shape[0])
        if not ks:
            raise InputError(f"{args.runfile}: the run file holds no frames")
        paths = _outputs(args.runfile, prefix, fmt, ks, args.force)
        try:
            if fmt == "xdmf":
                _write_xdmf(f, times, ks, paths)
            else:
                _write_frames(f, fmt, ks, paths)
        except (KeyError, IndexError, ValueError, TypeError) as exc:
            # A missing dataset, or one of the wrong shape or kind
            msg = " ".join(str(exc).split())
            raise InputError(f"{args.runfile}: not a complete pdfem run file ({msg})") from None
    where = paths[0] if fmt == "xdmf" else f"{prefix}-NNNN.{paths[0].rsplit('.', 1)[1]}"
    print(f"pdfem export: {len(ks)} frame(s) -> {where}")
    return 0
