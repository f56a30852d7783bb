"""Give freed heap memory back to the operating system.

Setting up a large run builds many temporary arrays (meshes, batches, the first rebuild);
numpy frees them, but glibc keeps the freed pages in its heap, so the resident set size
stays at the set-up peak. ``trim()`` asks glibc to return them (malloc_trim), so that the
resident size of a running simulation is what it actually holds.
"""

import ctypes
import ctypes.util
import gc

_LIBC = None


def trim():
    """Collect garbage and return free heap pages to the OS; False where libc has no
    malloc_trim (not glibc)."""
    global _LIBC
    gc.collect()
    if _LIBC is None:
        try:
            _LIBC = ctypes.CDLL(ctypes.util.find_library("c") or "libc.so.6")
        except OSError:
            _LIBC = False
    if not _LIBC or not hasattr(_LIBC, "malloc_trim"):
        return False
    _LIBC.malloc_trim(0)
    return True
