"""``python -m pdfem``: see :mod:`pdfem.cli`."""

import sys

from pdfem.cli import main

if __name__ == "__main__":
    sys.exit(main())
