"""What the analysis writes as text: JSON-ready copies of its results, and atomic writes."""

import math
import os

import numpy as np


def plain(v):
    """JSON-ready copy: numpy scalars to floats/ints, NaN/inf to None, arrays to lists."""
    if isinstance(v, dict):
        return {str(k): plain(x) for k, x in v.items()}
    if isinstance(v, (list, tuple, np.ndarray)):
        return [plain(x) for x in v]
    if isinstance(v, (bool, np.bool_)):
        return bool(v)
    if isinstance(v, (int, np.integer)):
        return int(v)
    if isinstance(v, (float, np.floating)):
        return float(v) if math.isfinite(v) else None
    return v


def write_atomic(path, text):
    """Write ``text`` to ``path`` atomically (a partial file, then a rename)."""
    with open(path + ".part", "w") as f:
        f.write(text)
    os.replace(path + ".part", path)
