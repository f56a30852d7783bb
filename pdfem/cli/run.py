"""``pdfem run [scene] [-o out.h5]``: run a scene (the default scene when none is given)."""

import os
from importlib import resources

from pdfem.errors import InputError

DEFAULT_SCENE = "shot912.toml"


def default_scene_path():
    """Path of the scene that runs when ``python -m pdfem`` gets no argument."""
    return str(resources.files("pdfem") / "scenes" / DEFAULT_SCENE)


def add_parser(sub):
    p = sub.add_parser("run", help="run a scene")
    p.add_argument("scene", nargs="?", default=None, help="scene TOML file (default: "
                   f"the packaged {DEFAULT_SCENE})")
    p.add_argument("-o", "--output", default=None, help="run file (overrides output.path)")
    p.add_argument("--force", action="store_true", help="overwrite an existing run file")
    p.add_argument("--quiet", action="store_true", help="no progress or report")
    p.add_argument("--restart", default=None, metavar="CHECKPOINT", help="continue from a "
                   "checkpoint (<run file>.ckpt.h5) of this scene, on any number of ranks")


def check_output_path(path, force, key="output.path"):
    """The output file must be new (or --force) and its folder writable."""
    folder = os.path.dirname(os.path.abspath(path))
    if not os.path.isdir(folder):
        raise InputError(f"{key}: folder {folder} does not exist")
    if not os.access(folder, os.W_OK):
        raise InputError(f"{key}: folder {folder} is not writable")
    if os.path.exists(path) and not force:
        raise InputError(f"{key}: {path} exists (use --force to overwrite)")


def run(args):
    from pdfem.driver import run as drive
    from pdfem.parallel.mpi import world
    from pdfem.scene import load_scene
    from pdfem.solver import Simulation

    comm = world()
    scene = load_scene(args.scene or default_scene_path())
    out = args.output or scene.resolved["output"]["path"]
    check_output_path(out, args.force)
    if comm.rank == 0 and not args.quiet:
        print(f"pdfem: {scene.path} on {comm.size} rank(s) -> {out}", flush=True)
    if args.restart and not os.path.isfile(args.restart):
        raise InputError(f"--restart: {args.restart}: no such checkpoint file")
    sim = Simulation(scene, comm, restart=args.restart)
    summary = drive(sim, out, quiet=args.quiet)
    if "shock" in scene.resolved and not summary["stopped"]:
        shock_report(out, summary, comm, args.quiet)
    return 0


def shock_report(out, summary, comm, quiet):
    """Analyse a finished shock run on rank 0: figures, summary JSON and text next to it."""
    import time

    from pdfem.analysis import analyse
    from pdfem.analysis.summary import report_text
    from pdfem.cli.analyse import prefix_of

    if comm.rank == 0:
        t0 = time.perf_counter()
        extra = {"wall_s": summary["wall_s"], "steps": summary["steps"], "ranks": comm.size,
                 "phases": {k: float(v[2]) for k, v in summary["phases"].items()}}
        result = analyse(out, prefix_of(out), extra=extra)
        if not quiet:
            print(report_text(result))
            print(f"analysis and figures in {time.perf_counter() - t0:.1f} s: "
                  f"{prefix_of(out)}-*.png, -summary.json, -summary.txt", flush=True)
    comm.Barrier()
