"""``pdfem run [scene] [-o out.h5]``: run a scene (the default scene when none is given)."""

import os
import sys

from pdfem.cli.paths import check_output_path, prefix_of
from pdfem.errors import InputError
from pdfem.limits import MAX_STEPS, add_allow_huge, check_step_count
from pdfem.packaged import DEFAULT_SCENE, default_scene_path

# Environment variable naming a file that rank 0 writes once every rank has ended the run
# cleanly (finished, or stopped with a checkpoint by SIGTERM or SIGUSR1): jobs/mpirun.sh reads
# it to tell a clean stop from a failure when mpirun's own exit status cannot (it exits 1
# after it was itself signalled, although every rank exited 0)
STATUS_ENV = "PDFEM_STATUS_FILE"


def add_parser(sub):
    p = sub.add_parser("run", help="run a scene")
    p.add_argument("scene", nargs="?", default=None, help="scene TOML file (default: "
                   f"the packaged {DEFAULT_SCENE})")
    p.add_argument("-o", "--output", default=None, help="run file (overrides output.path)")
    p.add_argument("--force", action="store_true", help="overwrite an existing run file")
    p.add_argument("--quiet", action="store_true", help="no progress or report")
    p.add_argument("--restart", default=None, metavar="CHECKPOINT", help="continue from a "
                   "checkpoint (<run file>.ckpt.h5) of this scene, on any number of ranks")
    add_allow_huge(p, f"more than {MAX_STEPS:.0e} steps")


def run_outputs(out, scene, plots=None, restart=None):
    """Every file a run of ``scene`` into ``out`` may leave: the run file, its XDMF sidecar,
    its checkpoint (unless it is the ``restart`` being continued) and, for a shock scene, the
    analysis (summary, and figures unless ``plots`` or the scene's shock.plots is "none")."""
    from pdfem.tools.analysis.summary import output_files, thermal_fields

    files = [out, os.path.splitext(out)[0] + ".xdmf"]
    if os.path.abspath(files[0]) == os.path.abspath(files[1]):
        raise InputError(f"output.path: {out}: the XDMF sidecar takes that name; use .h5")
    ckpt = out + ".ckpt.h5"
    if restart is None or os.path.abspath(restart) != os.path.abspath(ckpt):
        files.append(ckpt)
    if "shock" in scene.resolved:
        files += output_files(prefix_of(out), plots or scene.resolved["shock"]["plots"],
                              thermal_fields(scene.resolved["output"]["fields"]))
    return files


def run(args):
    from pdfem.scene import check_ranks, load_scene

    # The input first (a bad one is reported before MPI and the solver load)
    scene = load_scene(args.scene or default_scene_path())
    out = scene.resolved["output"]["path"] if args.output is None else args.output
    for path in run_outputs(out, scene, restart=args.restart):
        check_output_path(path, args.force)
    if args.restart and not os.path.isfile(args.restart):
        raise InputError(f"--restart: {args.restart}: no such checkpoint file")
    from pdfem.driver import run as drive
    from pdfem.parallel.mpi import world
    from pdfem.solver import Simulation

    comm = world()
    check_ranks(scene, comm.size)
    if comm.rank == 0 and not args.quiet:
        print(f"pdfem: {scene.path} on {comm.size} rank(s) -> {out}", flush=True)
    sim = Simulation(scene, comm, restart=args.restart)
    check_step_count(sim, scene.path, args.allow_huge)
    summary = drive(sim, out, quiet=args.quiet)
    if "shock" in scene.resolved and not summary["stopped"]:
        shock_report(out, summary, comm, args.quiet)
    write_status(os.environ.get(STATUS_ENV), summary, out, comm)
    return 0


def write_status(path, summary, out, comm):
    """When ``path`` is set: once every rank has got here, rank 0 writes one line to it,
    ``stopped <checkpoint>`` or ``done <run file>``. A file it cannot write is only warned
    about (it is what the launcher reads, not a result)."""
    from pdfem.parallel.mpi import barrier

    if not path:
        return
    barrier(comm)
    if comm.rank == 0:
        line = f"stopped {summary['checkpoint']}" if summary["stopped"] else f"done {out}"
        try:
            with open(path, "w") as f:
                f.write(line + "\n")
        except OSError as exc:
            print(f"pdfem: warning: {STATUS_ENV}: {path}: {exc.strerror}", file=sys.stderr,
                  flush=True)


def shock_report(out, summary, comm, quiet):
    """Analyse a finished shock run on rank 0: figures, summary JSON and text next to it."""
    import time

    from pdfem.parallel.mpi import barrier
    from pdfem.tools.analysis import analyse
    from pdfem.tools.analysis.report import report_text

    if comm.rank == 0:
        t0 = time.perf_counter()
        extra = {"wall_s": summary["wall_s"], "steps": summary["steps"], "ranks": comm.size,
                 "phases": {k: float(v[2]) for k, v in summary["phases"].items()},
                 "skipped_at_rest": summary["skipped_at_rest"]}
        result = analyse(out, prefix_of(out), extra=extra)
        if not quiet:
            print(report_text(result))
            print(f"analysis and figures in {time.perf_counter() - t0:.1f} s: "
                  f"{prefix_of(out)}-*.png, -summary.json, -summary.txt", flush=True)
    barrier(comm)
