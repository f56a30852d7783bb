"""``python -m pdfem``: see :mod:`pdfem.cli`."""

import sys

from pdfem import sigterm

# Before the heavy imports: a SIGTERM from here on ends a run with a checkpoint
sigterm.hold()

from pdfem.cli import main  # noqa: E402

if __name__ == "__main__":
    sys.exit(main())
