"""``pdfem analyse run.h5 [-p prefix]``: wave front, jump conditions, Hugoniot and figures of a
finished shock run (one with a [shock] table); the run command does this on its own."""

import os


def add_parser(sub):
    p = sub.add_parser("analyse", help="analyse a finished shock run: front, jump conditions, "
                       "Hugoniot, figures, summary")
    p.add_argument("runfile", help="run file (HDF5) of a scene with a [shock] table")
    p.add_argument("-p", "--prefix", default=None, help="prefix of the summary and figure "
                   "files (default: the run file without .h5)")
    p.add_argument("--force", action="store_true", help="overwrite existing summary and "
                   "figure files")
    p.add_argument("--sweep", default=None, metavar="JSON", help="a sweep's <prefix>.json "
                   "(pdfem sweep): its steady states and static curve join the jump-state "
                   "figure")


def _sweep(path):
    """The points and static curve of a sweep's JSON, or InputError naming --sweep."""
    import json

    from pdfem.errors import InputError

    try:
        with open(path) as fh:
            doc = json.load(fh)
    except OSError as exc:
        raise InputError(f"--sweep: {path}: cannot read: {exc.strerror}") from None
    except (UnicodeDecodeError, ValueError) as exc:
        raise InputError(f"--sweep: {path}: not a JSON file ({exc})") from None
    if not isinstance(doc, dict) or not isinstance(doc.get("points"), list):
        raise InputError(f"--sweep: {path}: not a sweep's JSON (no list of points)")
    for i, q in enumerate(doc["points"]):
        for key in ("us", "rho1", "sigma"):
            v = q.get(key) if isinstance(q, dict) else None
            if v is not None and (isinstance(v, bool) or not isinstance(v, (int, float))):
                raise InputError(f"--sweep: {path}: points[{i}].{key}: not a number")
    return {"points": doc["points"], "static": doc.get("static")}


def _plots(path):
    """([shock].plots of a run file's scene, whether its frames hold temperatures), or
    (None, False) when the file does not tell (then :func:`pdfem.tools.analysis.analyse` reports
    what is wrong with it)."""
    import tomllib

    import h5py

    from pdfem.tools.analysis.summary import thermal_fields

    try:
        with h5py.File(path, "r") as f:
            plots = tomllib.loads(str(f.attrs["scene"]))["shock"].get("plots", "png")
            return plots, thermal_fields(f["frames"]) if "frames" in f else False
    except (OSError, KeyError, TypeError, AttributeError, RuntimeError, ValueError,
            tomllib.TOMLDecodeError):
        return None, False


def run(args):
    from pdfem.cli.paths import check_output_path, prefix_of
    from pdfem.errors import InputError
    from pdfem.io.probe import check_metadata
    from pdfem.tools.analysis import analyse
    from pdfem.tools.analysis.report import report_text
    from pdfem.tools.analysis.summary import output_files

    if not args.runfile:
        raise InputError("runfile: empty file name")
    if not os.path.isfile(args.runfile):
        raise InputError(f"{args.runfile}: no such run file")
    # Damaged metadata can hang the HDF5 library: read it in a child process first
    check_metadata(args.runfile)
    sweep = None if args.sweep is None else _sweep(args.sweep)
    prefix = prefix_of(args.runfile) if args.prefix is None else args.prefix
    plots, thermal = _plots(args.runfile)
    if plots is not None:
        for path in output_files(prefix, plots, thermal):
            check_output_path(path, args.force, "--prefix")
    summary = analyse(args.runfile, prefix, sweep=sweep)
    print(report_text(summary))
    return 0
