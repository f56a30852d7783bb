"""``pdfem prepare scene.toml [-o bed.h5]``: prepare a granular bed (see pdfem.prepare)."""

import os

from pdfem.cli.paths import check_output_path
from pdfem.limits import add_allow_huge


def add_parser(sub):
    p = sub.add_parser("prepare", help="rain grains into a chamber, drop a weight, relax: "
                       "write a bed file for an impact scene")
    p.add_argument("scene", help="preparation scene (TOML with a [prepare] table)")
    p.add_argument("-o", "--output", default=None, help="bed file (overrides prepare.output)")
    p.add_argument("--force", action="store_true", help="overwrite an existing bed file")
    add_allow_huge(p, "a bed of more grains or sweeps than pdfem.prepare.size allows, a "
                   "rain phase of more than 1e9 steps")


def run(args):
    from pdfem.scene import load_scene

    scene = load_scene(args.scene)
    if "prepare" not in scene.resolved:
        from pdfem.errors import InputError

        raise InputError(f"{args.scene}: prepare: the scene has no [prepare] table")
    out = scene.resolved["prepare"]["output"] if args.output is None else args.output
    check_output_path(out, args.force, "prepare.output")
    out = os.path.abspath(out)
    # The size before MPI starts: an absurd bed is refused with its estimate
    from pdfem.prepare.size import check_size, describe

    grains = check_size(scene.resolved, args.scene, args.allow_huge)
    from pdfem.parallel.mpi import world
    from pdfem.prepare import prepare

    comm = world()
    if comm.rank == 0:
        print(f"pdfem: preparing {args.scene} ({describe(grains)}) on {comm.size} rank(s) -> "
              f"{out}", flush=True)
    prepare(args.scene, out, comm, allow_huge=args.allow_huge)
    return 0
