"""``pdfem bench {elements,contact,all}``: print single-core performance figures.

elements: element updates per second of both integration rules, numba kernels vs their
numpy twins (pdfem.bench.elements); with --material cap and/or --heat, the cost per
element-step of those effects in real solver steps beside the elastic baseline
(pdfem.bench.effects). contact: contact detection and force time per step on dense
grain beds of several sizes (pdfem.bench.contact). all: both. Figures are printed, never
asserted; run on one rank.
"""

from pdfem.errors import InputError


def _positive_int(name, text, least=1):
    """An integer >= least, or InputError naming the option."""
    try:
        value = int(text)
    except ValueError:
        raise InputError(f"bench: {name}: not an integer (got {text!r})") from None
    if value < least:
        raise InputError(f"bench: {name}: must be >= {least} (got {value})")
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
    p = sub.add_parser("bench", help="print single-core performance figures",
                       description=__doc__.split("\n\n")[1])
    what = p.add_subparsers(dest="what", metavar="{elements,contact,all}", required=True,
                            parser_class=type(p))
    # Arguments of each sub-command (all takes both sets)
    el = what.add_parser("elements", help="element force kernels: numba vs numpy")
    co = what.add_parser("contact", help="contact detection and forces on grain beds")
    al = what.add_parser("all", help="elements, then contact")
    for q in (el, al):
        q.add_argument("--n", default="100000", help="number of elements (default 100000)")
    el.add_argument("--material", default="elastic", choices=("elastic", "cap"),
                    help="material of the effect-cost table (default elastic)")
    el.add_argument("--heat", action="store_true", help="heat on in the effect-cost table")
    for q in (co, al):
        q.add_argument("--sizes", default="1000,10000,100000",
                       help="bed sizes in grains, comma-separated (default 1000,10000,100000)")
    for q in (el, co, al):
        q.add_argument("--repeat", default="5", help="timed samples; the median is printed "
                       "(default 5)")
    return p


def run(args):
    """Check the arguments, then run the chosen benchmarks on one rank."""
    from pdfem.parallel.mpi import world

    # Arguments first: a bad one costs no benchmark time
    repeat = _positive_int("--repeat", args.repeat)
    n = _positive_int("--n", args.n) if args.what in ("elements", "all") else None
    sizes = _sizes(args.sizes) if args.what in ("contact", "all") else None
    if world().size > 1:
        raise InputError("bench: runs on one rank (single-core figures); start it without "
                         "mpirun")
    from pdfem.bench.contact import print_contact
    from pdfem.bench.elements import print_elements

    # The chosen benchmarks, each printing its own table
    effects = args.what == "elements" and (args.material != "elastic" or args.heat)
    if effects:
        from pdfem.bench.effects import print_effects

        print_effects(n, repeat, args.material, args.heat, log=_log)
    elif n is not None:
        print_elements(n, repeat, log=_log)
    if n is not None and sizes is not None:
        _log("")
    if sizes is not None:
        print_contact(sizes, repeat, log=_log)
    return 0


def _log(line):
    """Print a line at once (benchmarks run long)."""
    print(line, flush=True)
