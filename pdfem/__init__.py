"""pdfem: parallel Discrete Finite Element Method for shock compression of granular media.

Every grain is its own small mesh of 4-node quads (updated Lagrangian, plane strain); grains
touch through the overlap contact of Ghaboussi & Joghataie (1997); the contact cell grid is
also the MPI domain decomposition. Results are bit-for-bit identical on any number of ranks.
"""

import time as _time

__version__ = "0.1.0"
# When pdfem was first imported (the start-up figure counts from here)
STARTED = _time.perf_counter()


def _numba_cache_dir():
    """Point numba's on-disk cache at a folder named after the kernel sources.

    numba's ``cache=True`` keys a function's cache on its own file only: a kernel that
    inlines a function of another module keeps its stale machine code when only that other
    module changes. A folder per hash of every pdfem source that holds a numba kernel makes
    any kernel change a fresh cache. NUMBA_CACHE_DIR set by the user wins.
    """
    import hashlib
    import os
    import sys
    from pathlib import Path

    if "NUMBA_CACHE_DIR" in os.environ:
        return
    root = Path(__file__).resolve().parent
    digest = hashlib.sha256(sys.version.encode())
    # Every module with a kernel, in a fixed order
    for path in sorted(root.rglob("*.py")):
        text = path.read_bytes()
        if b"njit" in text:
            digest.update(str(path.relative_to(root)).encode() + b"\0" + text)
    base = os.environ.get("XDG_CACHE_HOME") or os.path.join(os.path.expanduser("~"), ".cache")
    folder = os.path.join(base, "pdfem", "numba-" + digest.hexdigest()[:16])
    os.environ["NUMBA_CACHE_DIR"] = folder
    if "numba" in sys.modules:  # imported before pdfem: tell its live configuration too
        sys.modules["numba"].config.CACHE_DIR = folder


_numba_cache_dir()
