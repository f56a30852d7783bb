"""The C yardstick of the 1-point elastic element kernel: build with gcc, call with ctypes.

``load()`` compiles ``pdfem/bench/c/q4_1pt.c`` with ``gcc -O3 -march=native -shared -fPIC``
into a per-user cache folder (rebuilt when the source changes) and returns a Python callable
with the numba kernel's argument list (elastic only, no thermal coupling), or None when no C
compiler is available.
"""

import ctypes
import hashlib
import os
import shutil
import subprocess
import tempfile
from importlib import resources

import numpy as np

FLAGS = ["-O3", "-march=native", "-shared", "-fPIC"]


def _library():
    """Path of the built shared library, or None without gcc."""
    gcc = shutil.which("gcc") or shutil.which("cc")
    if gcc is None:
        return None
    src = resources.files("pdfem") / "bench" / "c" / "q4_1pt.c"
    text = src.read_bytes()
    tag = hashlib.sha256(text + " ".join(FLAGS).encode()).hexdigest()[:16]
    folder = os.path.join(tempfile.gettempdir(), f"pdfem-c-{os.getuid()}")
    os.makedirs(folder, exist_ok=True)
    lib = os.path.join(folder, f"q4_1pt-{tag}.so")
    if not os.path.exists(lib):
        tmp = lib + f".{os.getpid()}.part"
        subprocess.run([gcc, *FLAGS, "-o", tmp, str(src)], check=True, capture_output=True)
        os.replace(tmp, lib)
    return lib


def load():
    """A callable ``fn(x, du, conn, emat, mat, sig, mst, hgq, hg_coef, e0, e1, f, ewint, ewp,
    eth)`` running the C kernel (mst, ewp and eth are ignored: elastic, no heat), or None."""
    path = _library()
    if path is None:
        return None
    lib = ctypes.CDLL(path)
    fn = lib.q4_forces_1pt_elastic
    dbl, i64 = ctypes.c_double, ctypes.c_int64
    ptr = ctypes.c_void_p
    fn.argtypes = [ptr, ptr, ptr, ptr, ptr, i64, ptr, ptr, dbl, i64, i64, ptr, ptr]
    fn.restype = i64

    def call(x, du, conn, emat, mat, sig, mst, hgq, hg_coef, e0, e1, f, ewint, ewp, eth):
        arrays = (x, du, conn, emat, mat, sig, hgq, f, ewint)
        for a in arrays:
            if not a.flags.c_contiguous:
                raise ValueError("the C kernel needs C-contiguous arrays")
        assert conn.dtype == np.int64 and emat.dtype == np.int32
        return fn(x.ctypes.data, du.ctypes.data, conn.ctypes.data, emat.ctypes.data,
                  mat.ctypes.data, mat.shape[1], sig.ctypes.data, hgq.ctypes.data, hg_coef,
                  e0, e1, f.ctypes.data, ewint.ctypes.data)

    return call
