"""C yardsticks of the element kernels: build with gcc, call with ctypes.

``load(name)`` compiles ``pdfem/tools/bench/c/<name>.c`` with ``gcc -O3 -march=native -shared
-fPIC`` into a per-user cache folder (one .so per source, keyed by a hash of the source and
the flags, so an edited source is rebuilt) and returns a Python callable with the numba
kernel's argument list, or None when no C compiler is available:

    q4_1pt      pdfem.kernels.element.q4_forces_1pt, elastic materials only
    q4_2x2_cap  pdfem.kernels.element.q4_forces_2x2 with material state (cap, elastic), no
                thermal coupling
    contact_pass  pdfem.kernels.contact.contact_pass as a step calls it (key-sorted
                candidates, the history table, compact rows), convex elements; built with
                -ffp-contract=off too, so that its results are numba's bits
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
# Libraries linked after the source, and flags beyond FLAGS, per kernel
LIBS = {"q4_1pt": [], "q4_2x2_cap": ["-lm"], "contact_pass": ["-lm"]}
EXTRA = {"contact_pass": ["-ffp-contract=off"]}


def _library(name="q4_1pt"):
    """Path of the built shared library of pdfem/tools/bench/c/<name>.c, or None without gcc."""
    gcc = shutil.which("gcc") or shutil.which("cc")
    if gcc is None:
        return None
    src = resources.files("pdfem") / "tools" / "bench" / "c" / f"{name}.c"
    text = src.read_bytes()
    libs = LIBS[name]
    flags = FLAGS + EXTRA.get(name, [])
    tag = hashlib.sha256(text + " ".join(flags + libs).encode()).hexdigest()[:16]
    folder = os.path.join(tempfile.gettempdir(), f"pdfem-c-{os.getuid()}")
    os.makedirs(folder, exist_ok=True)
    lib = os.path.join(folder, f"{name}-{tag}.so")
    if not os.path.exists(lib):
        tmp = lib + f".{os.getpid()}.part"
        subprocess.run([gcc, *flags, "-o", tmp, str(src), *libs], check=True,
                       capture_output=True)
        os.replace(tmp, lib)
    return lib


def _check(arrays, floats):
    """C-contiguous arrays, float64 where the kernel reads doubles."""
    for a in arrays:
        if not a.flags.c_contiguous:
            raise ValueError("the C kernel needs C-contiguous arrays")
    for a in floats:
        if a.dtype != np.float64:
            raise ValueError("the C kernel needs float64 arrays")


def _load_1pt(lib):
    """Callable of the 1-point elastic kernel (mst, ewp and eth are ignored)."""
    fn = lib.q4_forces_1pt_elastic
    i64 = ctypes.c_int64
    ptr = ctypes.c_void_p
    fn.argtypes = [ptr, ptr, ptr, ptr, ptr, i64, ptr, ptr, i64, i64, i64, i64, ptr, ptr]
    fn.restype = i64

    def call(x, du, conn, emat, mat, sig, mst, hg, hg_model, e0, e1, f, ewint, ewp, eth):
        _check((x, du, conn, emat, mat, sig, hg, f, ewint), ())
        assert conn.dtype == np.int64 and emat.dtype == np.int32
        return fn(x.ctypes.data, du.ctypes.data, conn.ctypes.data, emat.ctypes.data,
                  mat.ctypes.data, mat.shape[1], sig.ctypes.data, hg.ctypes.data, hg.shape[0],
                  hg_model, e0, e1, f.ctypes.data, ewint.ctypes.data)

    return call


def _load_2x2_cap(lib):
    """Callable of the 2x2 kernel with material state (hg ignored as in numba)."""
    fn = lib.q4_forces_2x2_cap
    i64 = ctypes.c_int64
    ptr = ctypes.c_void_p
    fn.argtypes = [ptr, ptr, ptr, ptr, ptr, i64, ptr, ptr, i64, i64, i64, ptr, ptr, ptr]
    fn.restype = i64

    def call(x, du, conn, emat, mat, sig, mst, hg, hg_model, e0, e1, f, ewint, ewp, eth):
        _check((x, du, conn, emat, mat, sig, mst, f, ewint, ewp),
               (x, du, mat, sig, mst, f, ewint, ewp))
        assert conn.dtype == np.int64 and emat.dtype == np.int32
        if sig.shape[1] != 4:
            raise ValueError("q4_forces_2x2 needs sig of shape (ne, 4, 4)")
        if mst.shape[0] != sig.shape[0] or mst.shape[1] != 4 or mst.shape[2] < 6:
            raise ValueError("the C 2x2 cap kernel needs mst of shape (ne, 4, >= 6)")
        if eth.shape[0] > 0:
            raise ValueError("the C 2x2 cap kernel has no thermal coupling (eth (0, 3))")
        return fn(x.ctypes.data, du.ctypes.data, conn.ctypes.data, emat.ctypes.data,
                  mat.ctypes.data, mat.shape[1], sig.ctypes.data, mst.ctypes.data,
                  mst.shape[2], e0, e1, f.ctypes.data, ewint.ctypes.data, ewp.ctypes.data)

    return call


def _load_contact_pass(lib):
    """Callable of the contact pass (production mode: law rows by material pair, the history
    by merge, compact rows). Returns (rows, guarded, evaluated, unsupported)."""
    fn = lib.contact_pass_c
    i64, dbl, ptr = ctypes.c_int64, ctypes.c_double, ctypes.c_void_p
    fn.argtypes = [ptr] * 10 + [i64] + [ptr] * 4 + [i64, ptr, ptr, i64, dbl, i64, ptr, i64] + \
        [ptr] * 11
    fn.restype = i64

    def call(x, du, m, conn, ebnd, egid, eloc, elen, emat, law, nmat, wall_p0, wall_n, wall_mu,
             cand, hkey, hval, dt, bbox, active, keys, elems, nodes, weights, fnod, us_out, res):
        floats = (x, du, m, elen, law, wall_p0, wall_n, wall_mu, hval, bbox, weights, fnod,
                  us_out, res)
        ints = (conn, egid, eloc, cand, hkey, keys, elems, nodes)
        _check(floats + ints + (ebnd, emat, active), floats)
        assert all(a.dtype == np.int64 for a in ints) and emat.dtype == np.int32
        assert ebnd.dtype == np.int8 and active.dtype == np.int8
        out = (ctypes.c_int64(), ctypes.c_int64(), ctypes.c_int64())
        n = fn(x.ctypes.data, du.ctypes.data, m.ctypes.data, conn.ctypes.data, ebnd.ctypes.data,
               egid.ctypes.data, eloc.ctypes.data, elen.ctypes.data, emat.ctypes.data,
               law.ctypes.data, nmat, wall_p0.ctypes.data, wall_n.ctypes.data,
               wall_mu.ctypes.data, cand.ctypes.data, cand.shape[0], hkey.ctypes.data,
               hval.ctypes.data, hkey.shape[0], dt, conn.shape[0], bbox.ctypes.data,
               active.shape[0], active.ctypes.data, keys.ctypes.data, elems.ctypes.data,
               nodes.ctypes.data, weights.ctypes.data, fnod.ctypes.data, us_out.ctypes.data,
               res.ctypes.data, *(ctypes.byref(o) for o in out))
        return n, out[0].value, out[1].value, out[2].value

    return call


def load(name="q4_1pt"):
    """A callable running the C kernel ``name`` (see the module docstring), or None without
    gcc: for the element kernels ``fn(x, du, conn, emat, mat, sig, mst, hg, hg_model, e0,
    e1, f, ewint, ewp, eth)``, for contact_pass the arguments of a step's pass (_load_contact_pass).
    """
    makers = {"q4_1pt": _load_1pt, "q4_2x2_cap": _load_2x2_cap,
              "contact_pass": _load_contact_pass}
    if name not in makers:
        raise ValueError(f"unknown C yardstick {name!r} (have {', '.join(makers)})")
    path = _library(name)
    if path is None:
        return None
    return makers[name](ctypes.CDLL(path))
