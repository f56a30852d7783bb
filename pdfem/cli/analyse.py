"""``pdfem analyse run.h5 [-p prefix]``: wave front, jump conditions, Hugoniot and figures of a
finished shock run (one with a [shock] table); the run command does this on its own."""

import os


def add_parser(sub):
    p = sub.add_parser("analyse", help="analyse a finished shock run: front, jump conditions, "
                       "Hugoniot, figures, summary")
    p.add_argument("runfile", help="run file (HDF5) of a scene with a [shock] table")
    p.add_argument("-p", "--prefix", default=None, help="prefix of the summary and figure "
                   "files (default: the run file without .h5)")


def prefix_of(path):
    """``shot912.h5`` -> ``shot912``."""
    root, ext = os.path.splitext(path)
    return root if ext in (".h5", ".hdf5") else path


def run(args):
    from pdfem.analysis import analyse
    from pdfem.analysis.summary import report_text
    from pdfem.errors import InputError

    if not os.path.isfile(args.runfile):
        raise InputError(f"{args.runfile}: no such run file")
    summary = analyse(args.runfile, args.prefix or prefix_of(args.runfile))
    print(report_text(summary))
    return 0
