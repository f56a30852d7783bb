"""``pdfem sweep scene.toml --velocities 100,200,...``: the shock scene at several hammer
speeds; Us-up and stress-density points beside the snowplow bound (report fig. 13 style)."""

import json
import math
import os
import tomllib

from pdfem.errors import InputError


def add_parser(sub):
    p = sub.add_parser("sweep", help="run a shock scene at several hammer velocities: Us-up "
                       "and stress-density points with the snowplow bound")
    p.add_argument("scene", nargs="?", default=None, help="scene with a [shock] table "
                   "(default: the packaged shot912.toml)")
    p.add_argument("--velocities", default="100,200,288,400,500",
                   help="hammer speeds [m/s], comma separated (default 100,200,288,400,500)")
    p.add_argument("-p", "--prefix", default="sweep", help="prefix of the run files, "
                   "sweep.json and sweep.png (default: sweep)")
    p.add_argument("--force", action="store_true", help="overwrite existing run files")


def _speeds(text):
    """The --velocities list: positive floats."""
    try:
        vals = [float(v) for v in text.split(",") if v.strip()]
    except ValueError:
        raise InputError(f"--velocities: not a list of numbers: {text!r}") from None
    if not vals or any(not 0.0 < v < math.inf for v in vals):
        raise InputError(f"--velocities: need speeds > 0 m/s, finite (got {text!r})")
    return vals


def run(args):
    from pdfem.cli.run import check_output_path, default_scene_path, run_outputs
    from pdfem.scene import check_ranks, load_scene, parse_scene

    # The input first (a bad one is reported before MPI and the solver load)
    speeds = _speeds(args.velocities)
    path = args.scene or default_scene_path()
    scene = load_scene(path)
    if "shock" not in scene.resolved:
        raise InputError(f"{path}: shock: sweep needs a scene with a [shock] table")
    hammer = scene.resolved["shock"]["hammer"]
    outs = [f"{args.prefix}-v{v:g}.h5" for v in speeds]
    # The runs (plots off: summaries only) and the sweep's own JSON and figure
    files = [f for o in outs for f in run_outputs(o, scene, plots="none")]
    for out in files + [args.prefix + ".json", args.prefix + ".png"]:
        check_output_path(out, args.force, "--prefix")
    from pdfem.analysis import analyse
    from pdfem.analysis.plots import sweep_plot
    from pdfem.driver import run as drive
    from pdfem.parallel.mpi import world
    from pdfem.solver import Simulation

    comm = world()
    check_ranks(scene, comm.size)
    with open(path, "rb") as fh:
        doc = tomllib.load(fh)
    points = []
    for v, out in zip(speeds, outs, strict=True):
        # The scene with the hammer's initial velocity replaced
        for blk in doc["blocks"]:
            if blk["name"] == hammer:
                blk["velocity"] = [0.0, -v]
        doc.setdefault("shock", {})["plots"] = "none"
        sc = parse_scene(doc, scene.base_dir, name=f"{path} (hammer at {v:g} m/s)")
        if comm.rank == 0:
            print(f"pdfem sweep: hammer at {v:g} m/s -> {out}", flush=True)
        summary = drive(Simulation(sc, comm), out, quiet=True)
        if comm.rank == 0:
            s = analyse(out, os.path.splitext(out)[0])
            points.append({"velocity": v, "us": s["front"]["us"], "up": s["shocked"]["up"],
                           "sigma": s["shocked"]["sigma_hammer_deceleration"],
                           "sigma_bed": s["shocked"]["sigma_bed"],
                           "sigma_gauge": s["shocked"]["sigma"], "rho0": s["bed"]["rho0"],
                           "rho1": s["shocked"]["rho1"],
                           "solid_density": s["bed"]["solid_density"],
                           "snowplow_us": s["snowplow"]["us"],
                           "snowplow_sigma": s["snowplow"]["sigma"],
                           "mass_closure": s["jump"]["mass_closure"],
                           "momentum_closure": s["jump"]["momentum_closure_deceleration"],
                           "balance_error": summary["balance_error"], "wall_s": summary["wall_s"]})
            p = points[-1]
            print(f"  Us {_f(p['us'])} m/s, up {_f(p['up'])} m/s, stress (hammer deceleration) "
                  f"{_f(p['sigma'], 1e-6)} MPa, behind the front {_f(p['sigma_bed'], 1e-6)} MPa; "
                  f"snowplow Us {_f(p['snowplow_us'])} m/s", flush=True)
    if comm.rank == 0:
        from pdfem.analysis.summary import _plain

        with open(args.prefix + ".json.part", "w") as fh:
            json.dump(_plain(points), fh, indent=1)
        os.replace(args.prefix + ".json.part", args.prefix + ".json")
        sweep_plot(points, args.prefix + ".png")
        print(f"pdfem sweep: {args.prefix}.json, {args.prefix}.png", flush=True)
    comm.Barrier()
    return 0


def _f(v, scale=1.0):
    """A number for the log line, or n/a."""
    return "n/a" if v is None or v != v else f"{v * scale:.1f}"
