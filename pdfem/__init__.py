"""pdfem: parallel Discrete Finite Element Method for shock compression of granular media.

Every grain is its own small mesh of 4-node quads (updated Lagrangian, plane strain); grains
touch through the overlap contact of Ghaboussi & Joghataie (1997); the contact cell grid is
also the MPI domain decomposition. Results are bit-for-bit identical on any number of ranks.
"""

import time as _time

__version__ = "0.1.0"
# When pdfem was first imported (the start-up figure counts from here)
STARTED = _time.perf_counter()
