"""``pdfem hotspots run.h5 [-o prefix]``: the hot-spot census of a thermal run.

Per frame, over the whole bed and (a shock run) behind the compaction front: the
mass-weighted temperature distribution, the area hotter than each threshold, and the hot
spots (connected hot regions) with their size, peak, site and heating mechanism; for a shock
run also the temperature against time since the front arrived. Writes
``<prefix>-hotspots.csv``, ``-hotspots-spots.csv``, ``-hotspots.json``,
``-hotspots-front.csv`` (shock runs) and the figures (definitions:
:mod:`pdfem.tools.analysis.hotspots`, docs/validation/hotspots.md).
"""

import math
import os

from pdfem.errors import InputError


def add_parser(sub):
    p = sub.add_parser("hotspots", help="hot-spot census of a thermal run: temperature "
                       "distribution, hot area, hot spots, front-relative history")
    p.add_argument("runfile", help="run file (HDF5) with temperatures")
    p.add_argument("-o", "-p", "--prefix", dest="prefix", default=None,
                   help="prefix of the output files (default: the run file without .h5)")
    add_threshold_options(p)
    p.add_argument("--contact-tol", default="0.1", help="distance at which boundary edges "
                   "of two bodies touch, in element sizes (default 0.1)")
    p.add_argument("--corner-angle", default="40", help="turning angle [degrees] of the "
                   "boundary at a grain corner (default 40)")
    p.add_argument("--plots", default="png", help="figure format: png (default), pdf, none")
    p.add_argument("--force", action="store_true", help="overwrite existing output files")


def add_threshold_options(p):
    """--thresholds and --spot-threshold of the census (also study hotspots')."""
    p.add_argument("--thresholds", default="400,500,600", help="temperatures [K] of the hot "
                   "area fractions, comma-separated (default 400,500,600)")
    p.add_argument("--spot-threshold", default=None, help="temperature [K] above which "
                   "elements form hot spots (default: the middle threshold)")


def thresholds_of(args):
    """(sorted thresholds, spot threshold or None) from the options of
    :func:`add_threshold_options`; InputError naming the option when one is bad."""
    parts = [s.strip() for s in str(args.thresholds).split(",")]
    if not parts or any(not s for s in parts):
        raise InputError(f"--thresholds: expected temperatures separated by commas (got "
                         f"{args.thresholds!r})")
    thr = sorted({_number(s, "--thresholds") for s in parts})
    spot = None if args.spot_threshold is None else _number(args.spot_threshold,
                                                            "--spot-threshold")
    return thr, spot


def _number(text, option, lo=0.0, hi=math.inf, lo_open=True):
    """A finite float from ``text`` in (lo, hi) (or [lo, hi) without ``lo_open``)."""
    try:
        v = float(text)
    except (TypeError, ValueError):
        raise InputError(f"{option}: expected a number (got {text!r})") from None
    ok = math.isfinite(v) and (v > lo if lo_open else v >= lo) and v < hi
    if not ok:
        rng = f"{'(' if lo_open else '['}{lo:g}, {hi:g})"
        raise InputError(f"{option}: {text!r} out of range {rng}")
    return v


def _options(args):
    """(thresholds, spot threshold, contact tolerance, corner angle, plots) from ``args``."""
    from pdfem.tools.analysis.hotwrite import PLOT_FORMATS

    thr, spot = thresholds_of(args)
    tol = _number(args.contact_tol, "--contact-tol", 0.0, lo_open=False)
    corner = _number(args.corner_angle, "--corner-angle", 0.0, 180.0)
    if args.plots not in PLOT_FORMATS:
        raise InputError(f"--plots: expected one of {', '.join(PLOT_FORMATS)} (got "
                         f"{args.plots!r})")
    return thr, spot, tol, corner, args.plots


def _shock(path):
    """Whether the run's scene has a [shock] table; None when the file does not tell (the
    census then reports what is wrong with it)."""
    import tomllib

    import h5py

    try:
        with h5py.File(path, "r") as f:
            return "shock" in tomllib.loads(str(f.attrs["scene"]))
    except (OSError, KeyError, TypeError, AttributeError, tomllib.TOMLDecodeError):
        return None


def _k(v):
    """A temperature to 0.1 K, or n/a."""
    return "n/a" if v is None or not math.isfinite(v) else f"{v:.1f}"


def _report(result, paths):
    """The short text report of a census."""
    last = result["frames"][-1]
    s = result["settings"]
    lines = [f"Hot-spot census of {result['file']}: {result['n_frames']} frame(s), "
             f"{result['n_grain_elements']} grain elements, T from "
             f"/frames/{result['temperature_field']}"]
    for region in result["regions"]:
        d = last[region]
        name = "whole bed" if region == "whole" else "behind the front"
        lines.append(f"  last frame (t = {last['time'] * 1e6:.3f} us), {name}: mean "
                     f"{_k(d['mean'])} K, p50 {_k(d['p50'])}, p90 {_k(d['p90'])}, p99 "
                     f"{_k(d['p99'])}, p99.9 {_k(d['p99.9'])}, max {_k(d['max'])} K; "
                     f"{d['n_spots']} spot(s) above {s['spot_threshold']:g} K")
    peak = max(result["frames"], key=lambda f: f["whole"]["n_spots"])
    lines.append(f"  most spots: {peak['whole']['n_spots']} at t = {peak['time'] * 1e6:.3f} us; "
                 f"{len(result['spots'])} spot rows in all")
    lines += [f"  note: {n}" for n in result["notes"]]
    lines.append("wrote " + ", ".join(paths))
    return "\n".join(lines)


def run(args):
    from pdfem.cli.paths import check_output_path, prefix_of
    from pdfem.tools.analysis.hotcensus import census
    from pdfem.tools.analysis.hotwrite import output_files, write_outputs

    if not args.runfile:
        raise InputError("runfile: empty file name")
    if not os.path.isfile(args.runfile):
        raise InputError(f"{args.runfile}: no such run file")
    thr, spot, tol, corner, plots = _options(args)
    # Damaged metadata can hang the HDF5 library: read it in a child process first
    from pdfem.io.probe import check_metadata

    check_metadata(args.runfile)
    prefix = prefix_of(args.runfile) if args.prefix is None else args.prefix
    shock = _shock(args.runfile)
    # Refuse before the census when an output exists, and again once the census says
    # whether the run is a shock run (the front files)
    for path in output_files(prefix, plots, bool(shock)) if shock is not None else ():
        check_output_path(path, args.force, "--prefix")
    result, maps = census(args.runfile, thr, spot, tol, corner)
    paths = output_files(prefix, plots, result["front"] is not None)
    for path in paths:
        check_output_path(path, args.force, "--prefix")
    write_outputs(result, maps, prefix, plots)
    print(_report(result, paths))
    return 0
