"""``pdfem bench {elements,contact,peers,parallel,checkpoint,startup,job,all}``: print
performance figures.

elements: element updates per second of both integration rules, numba kernels vs their
numpy twins and the 1-point kernel vs its C yardstick (pdfem.tools.bench.elements); with
--material cap and/or --heat, the cost per element-step of those effects in real solver steps
(pdfem.tools.bench.effects). contact: whole steps of dense grain beds of several sizes,
contact and element time, memory per grain, the contact pass against its C twin
(pdfem.tools.bench.contact). peers: the 10^4-grain cap bed against a LAMMPS bed of 10^4
frictional discs, when lmp is on the PATH (pdfem.tools.bench.peers). parallel: halo and
migration cost, under mpirun (pdfem.tools.bench.parallel). checkpoint: the time of a
checkpoint's write and of a restart's set-up, and rank 0's memory during both, on any number
of ranks (pdfem.tools.bench.checkpoint). startup: seconds to the first step of a fresh process
(pdfem.tools.bench.startup). job: the default job (mpirun -n 2 python -m pdfem, run in a
scratch folder, or a summary it wrote) in units of the 10^3-grain cap bed's step
(pdfem.tools.bench.job). all: every figure with its target (pdfem.tools.bench.suite).
Figures are printed, never asserted; all but parallel and checkpoint run on one rank.
"""

import json
import os

from pdfem.errors import InputError

# The largest sizes and repeat count taken (more is a typo: memory or time would run out)
MOST = {"--grains": 10**7, "--n": 10**7, "--sizes": 10**7, "--per-rank": 10**7,
        "--repeat": 1000}


def _positive_int(name, text, least=1):
    """An integer in [least, MOST[name]], or InputError naming the option."""
    try:
        value = int(text)
    except ValueError:
        raise InputError(f"bench: {name}: not an integer (got {text!r})") from None
    if not least <= value <= MOST[name]:
        raise InputError(f"bench: {name}: must be in [{least}, {MOST[name]}] (got {value})")
    return value


def _sizes(text):
    """Comma-separated bed sizes (grains, each >= 2), sorted, without duplicates."""
    parts = [p.strip() for p in text.split(",") if p.strip()]
    if not parts:
        raise InputError(f"bench: --sizes: expected a comma-separated list of grain counts "
                         f"(got {text!r})")
    return sorted({_positive_int("--sizes", p, least=2) for p in parts})


def add_parser(sub):
    """Register the ``bench`` command and its sub-commands."""
    p = sub.add_parser("bench", help="print performance figures",
                       description=__doc__.split("\n\n")[1])
    what = p.add_subparsers(dest="what", required=True, parser_class=type(p),
                            metavar="{elements,contact,peers,parallel,checkpoint,startup,job,all}")
    # Arguments of each sub-command (all takes the union)
    el = what.add_parser("elements", help="element force kernels: numba vs numpy and C")
    co = what.add_parser("contact", help="whole steps of dense grain beds")
    pe = what.add_parser("peers", help="the 10^4-grain cap bed against a LAMMPS disc bed (lmp "
                         "on the PATH)")
    pa = what.add_parser("parallel", help="halo and migration cost (run under mpirun)")
    ck = what.add_parser("checkpoint", help="checkpoint write and restart: time, rank 0's "
                         "memory (any number of ranks)")
    su = what.add_parser("startup", help="seconds to the first step, cold and warm")
    jo = what.add_parser("job", help="the default job's wall time over the machine's yardstick")
    al = what.add_parser("all", help="every figure with its target")
    for q in (el, al):
        q.add_argument("--n", default="100000", help="number of elements (default 100000)")
    el.add_argument("--material", default="elastic", choices=("elastic", "cap"),
                    help="material of the effect-cost table (default elastic)")
    el.add_argument("--heat", action="store_true", help="heat on in the effect-cost table")
    co.add_argument("--material", default="elastic", choices=("elastic", "cap"),
                    help="grain material (default elastic)")
    for q in (co, al):
        q.add_argument("--sizes", default="1000,10000,100000",
                       help="bed sizes in grains, comma-separated (default 1000,10000,100000)")
    for q in (pa, al):
        q.add_argument("--per-rank", default="10000", help="grains per rank (default 10000)")
    pa.add_argument("--json", default=None, help="also write the figures to this JSON file")
    pa.add_argument("--force", action="store_true", help="overwrite an existing JSON file")
    ck.add_argument("--grains", default="100000", help="grains of the bed (default 100000)")
    pe.add_argument("--grains", default="10000", help="grains of pdfem's bed (default 10000, "
                    "the comparison's)")
    for q in (su, al):
        q.add_argument("--warm-only", action="store_true", help="skip the cold start (a "
                       "private empty numba cache: every kernel compiled, about 30 s)")
    jo.add_argument("--summary", default=None, help="a summary JSON of the default job "
                    "(<run>-summary.json) instead of running it")
    for q in (el, co, pe, pa, ck, su, jo, al):
        q.add_argument("--repeat", default="5", help="timed samples; the median is printed "
                       "(default 5)")
    return p


def run(args):
    """Check the arguments, then run the chosen benchmarks."""
    # Arguments first: a bad one costs no benchmark time (nor MPI's start)
    repeat = _positive_int("--repeat", args.repeat)
    n = _positive_int("--n", args.n) if hasattr(args, "n") else None
    grains = _positive_int("--grains", args.grains, least=2) if hasattr(args, "grains") else None
    sizes = _sizes(args.sizes) if hasattr(args, "sizes") else None
    per_rank = _positive_int("--per-rank", args.per_rank, least=2) \
        if hasattr(args, "per_rank") else None
    if args.what == "parallel" and args.json is not None:
        from pdfem.cli.paths import check_output_path

        check_output_path(args.json, args.force, "--json")
    from pdfem.parallel.mpi import world

    if args.what == "parallel":
        from pdfem.tools.bench.parallel import print_parallel

        if world().size < 2:
            raise InputError("bench parallel: start it under mpirun with 2 or more ranks")
        r = print_parallel(per_rank, repeat, log=_log)
        if args.json and world().rank == 0:
            with open(args.json + ".part", "w") as f:
                json.dump(r, f)
            os.replace(args.json + ".part", args.json)
        return 0
    if args.what == "checkpoint":
        from pdfem.tools.bench.checkpoint import print_checkpoint

        print_checkpoint(grains, repeat, log=_log)
        return 0
    if world().size > 1:
        raise InputError(f"bench {args.what}: runs on one rank (single-core figures); start it "
                         "without mpirun")
    # The chosen benchmark, printing its own table
    if args.what == "all":
        from pdfem.tools.bench.suite import run_all

        run_all(repeat, n, sizes, per_rank, log=_log, cold=not args.warm_only)
    elif args.what == "elements" and (args.material != "elastic" or args.heat):
        from pdfem.tools.bench.effects import print_effects

        print_effects(n, repeat, args.material, args.heat, log=_log)
    elif args.what == "elements":
        from pdfem.tools.bench.elements import print_elements

        print_elements(n, repeat, log=_log)
    elif args.what == "contact":
        from pdfem.tools.bench.contact import print_contact

        print_contact(sizes, repeat, log=_log, material=args.material)
    elif args.what == "job":
        from pdfem.tools.bench.job import print_job

        print_job(repeat, args.summary, log=_log)
    elif args.what == "peers":
        from pdfem.tools.bench.peers import print_peers

        print_peers(repeat, log=_log, grains=grains)
    else:
        from pdfem.tools.bench.startup import print_startup

        print_startup(repeat, cold=not args.warm_only, log=_log)
    return 0


def _log(line):
    """Print a line at once (benchmarks run long)."""
    print(line, flush=True)
