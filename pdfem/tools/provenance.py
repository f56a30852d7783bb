"""Where a study's figures came from: the date, the commit, the machine and the ranks.

Written beside a study's rows (``study speeds``, ``sweep``) so that a table made from them can
name the commit and machine of every row, as the documentation's tables do.
"""

import datetime
import os
import subprocess

from pdfem import __version__


def commit():
    """The short hash of the git checkout pdfem is imported from, ending in ``+`` when tracked
    files differ from it; None outside a checkout or without git."""
    here = os.path.dirname(os.path.abspath(__file__))
    try:
        head = subprocess.run(["git", "-C", here, "rev-parse", "--short", "HEAD"],
                              capture_output=True, text=True, timeout=30)
        if head.returncode != 0:
            return None
        dirty = subprocess.run(["git", "-C", here, "status", "--porcelain",
                                "--untracked-files=no"], capture_output=True, text=True,
                               timeout=30)
    except (OSError, subprocess.SubprocessError):
        return None
    return head.stdout.strip() + ("+" if dirty.stdout.strip() else "")


def provenance(ranks):
    """A dict: UTC date and time, pdfem's version and commit, the machine line of the
    benchmarks and the number of ranks."""
    from pdfem.tools.bench.elements import machine

    now = datetime.datetime.now(datetime.UTC)
    return {"date": now.strftime("%Y-%m-%d %H:%M UTC"), "pdfem_version": __version__,
            "commit": commit(), "ranks": int(ranks),
            "machine": machine().replace("one core", f"{ranks} rank(s)")}
