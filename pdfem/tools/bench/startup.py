"""``pdfem bench startup``: seconds from the command to the first step, cold and warm.

Runs ``python -m pdfem run`` on the packaged default scene cut to one step (time.max_steps
= 1, output into a temporary folder) in fresh processes: the first run after the numba
cache folder was emptied (compiles every kernel), then runs with the cache filled. The run
prints "first step at X s" (from process start, measured in the driver); the figure is the
median of the warm runs. The target is a warm start within 10 s.
"""

import os
import re
import shutil
import statistics
import subprocess
import sys
import tempfile
import time

from pdfem.tools.bench.elements import machine


def _scene(folder):
    """The default scene with one step and its output in folder; returns the scene path."""
    from pdfem.packaged import default_scene_path

    src = default_scene_path()
    with open(src) as f:
        text = f.read()
    # One step; run file in the folder; the bed file by absolute path
    text = text.replace("[time]", "[time]\nmax_steps = 1", 1)
    base = os.path.dirname(os.path.abspath(src))
    text = re.sub(r'path = "([^"/]+\.h5)"', lambda m: f'path = "{os.path.join(base, m[1])}"'
                  if "bed" in m[1] else f'path = "{os.path.join(folder, m[1])}"', text)
    path = os.path.join(folder, "startup.toml")
    with open(path, "w") as f:
        f.write(text)
    return path


def _one(scene, env):
    """(wall seconds of the process, first-step seconds it printed or nan)."""
    t0 = time.perf_counter()
    p = subprocess.run([sys.executable, "-m", "pdfem", "run", scene, "--force"], env=env,
                       capture_output=True, text=True)
    wall = time.perf_counter() - t0
    if p.returncode != 0:
        raise RuntimeError(f"bench startup: the run failed: {p.stderr.strip()[-300:]}")
    m = re.search(r"first step at ([0-9.]+) s", p.stdout + p.stderr)
    return wall, float(m[1]) if m else float("nan")


def print_startup(repeat, cold=True, log=print):
    """Time the cold and warm starts; print them; return a dict."""
    folder = tempfile.mkdtemp(prefix="pdfem-startup-")
    env = dict(os.environ)
    # A private numba cache: the cold run compiles, the rest load the cache (without the
    # cold run: the user's own cache, filled by the run before the timed ones)
    if cold:
        env["NUMBA_CACHE_DIR"] = os.path.join(folder, "numba-cache")
    try:
        scene = _scene(folder)
        log("pdfem bench startup: python -m pdfem run <default scene, 1 step>, fresh processes"
            + (", a private numba cache" if cold else ", the numba cache as it is"))
        log(machine())
        out = {}
        if cold:
            out["cold"] = _one(scene, env)
            log(f"cold (cache empty, every kernel compiled): first step at {out['cold'][1]:.2f} "
                f"s, process {out['cold'][0]:.2f} s")
        else:
            _one(scene, env)
        warm = [_one(scene, env) for _ in range(repeat)]
        out["warm"] = statistics.median(w[1] for w in warm)
        out["warm_wall"] = statistics.median(w[0] for w in warm)
        log(f"warm (cache filled): first step at {out['warm']:.2f} s, process "
            f"{out['warm_wall']:.2f} s (median of {repeat}; target: first step within 10 s)")
        return out
    finally:
        shutil.rmtree(folder, ignore_errors=True)
