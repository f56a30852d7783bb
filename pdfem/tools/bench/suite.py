"""``pdfem bench all``: every performance figure of the project, each beside its target.

In order: the element kernels against their C yardsticks (1-point elastic, 2x2 cap), the
settled cap bed at 10^3, 10^4 and 10^5 grains (step time per grain-step, linearity, memory per
grain, the contact pass against its C twin), the 10^4-grain bed against the LAMMPS disc bed
(pdfem.tools.bench.peers, when lmp is on the PATH), the parallel overhead on 2 ranks (a child
``mpirun -n 2 ... bench parallel``) and the start-up time (child processes). Each figure is
the median of ``repeat`` samples. The closing table lists figure, measured value, target and
whether the target is met.
"""

import json
import os
import shutil
import subprocess
import sys
import tempfile

from pdfem.tools.bench.elements import machine, mesh_shape

# Performance targets
TARGETS = {
    "numba/C 1pt elastic": 1.6,
    "numba/C 2x2 cap": 2.0,
    "step us/grain-step, largest cap bed": 1.5,
    "10^4 cap bed / LAMMPS disc-step, CPU": 10.0,
    "linearity, largest/smallest bed": 1.2,
    "kB/grain, largest bed": 10.0,
    "parallel overhead %": 10.0,
    "warm start s": 10.0,
}


def mpirun_command(n):
    """argv prefix starting n ranks with the mpirun on PATH (Open MPI: root and
    oversubscription allowed, no single-copy shared memory, as jobs/mpirun.sh), or None."""
    exe = shutil.which("mpirun") or shutil.which("mpiexec")
    if exe is None:
        return None
    cmd = [exe, "-n", str(n)]
    if "Open MPI" in subprocess.run([exe, "--version"], capture_output=True, text=True).stdout:
        cmd[1:1] = (["--oversubscribe", "--mca", "btl_vader_single_copy_mechanism", "none"]
                    + (["--allow-run-as-root"] if os.getuid() == 0 else []))
    return cmd


def child_mpi_env():
    """This process's environment without its MPI variables: it may be an MPI singleton, whose
    variables must not reach a child mpirun."""
    return {k: v for k, v in os.environ.items()
            if not k.startswith(("OMPI_MCA_", "OMPI_COMM", "OMPI_FILE", "PMIX_", "PMI_"))}


def _parallel(per_rank, repeat, log):
    """The parallel figures from a child mpirun of 2 ranks (its output relayed), or None."""
    cmd = mpirun_command(2)
    if cmd is None:
        log("bench parallel: no mpirun on PATH, skipped")
        return None
    with tempfile.TemporaryDirectory() as folder:
        out = os.path.join(folder, "parallel.json")
        env = child_mpi_env()
        p = subprocess.run(cmd + [sys.executable, "-m", "pdfem", "bench", "parallel",
                                  "--per-rank", str(per_rank), "--repeat", str(repeat),
                                  "--json", out], capture_output=True, text=True, env=env)
        for line in p.stdout.splitlines():
            log(line)
        if p.returncode != 0 or not os.path.exists(out):
            why = (p.stderr.strip() or p.stdout.strip())[-300:]
            log(f"bench parallel failed (exit {p.returncode}): {why}")
            return None
        with open(out) as f:
            return json.load(f)


def run_all(repeat, n_elements, sizes, per_rank, log=print, cold=True):
    """Run every benchmark, print each table, then the summary; return the summary rows."""
    from pdfem.tools.bench.cap_yardstick import c_yardstick_cap
    from pdfem.tools.bench.contact import print_contact
    from pdfem.tools.bench.elements import print_elements
    from pdfem.tools.bench.startup import print_startup

    got = {}
    log(machine())
    # 1. Element kernels and their C yardsticks
    _, c1 = print_elements(n_elements, repeat, log=log)
    if c1 is not None:
        got["numba/C 1pt elastic"] = c1["numba"] / c1["c"]
    log("")
    nx, ny = mesh_shape(n_elements)
    c4 = c_yardstick_cap(nx, ny, repeat)
    if c4 is None:
        log("C yardstick 2x2 cap: no C compiler found (gcc or cc), skipped")
    else:
        ne = c4["elements"]
        log(f"C yardstick 2x2 cap (gcc -O3 -march=native), {ne} elements, "
            f"{100 * c4['yield_fraction']:.0f} % of the points yielding: numba "
            f"{1e9 * c4['numba'] / ne:.1f} ns/elem-update, C {1e9 * c4['c'] / ne:.1f} "
            f"ns/elem-update, numba/C = {c4['ratio']:.2f} (target <= 2; largest relative "
            f"difference of the results {c4['diff']:.1e})")
        got["numba/C 2x2 cap"] = c4["ratio"]
    log("")
    # 2. The settled cap bed: step time, linearity, memory
    rows = print_contact(sizes, repeat, log=log, material="cap")
    lo, hi = rows[0], rows[-1]
    got["step us/grain-step, largest cap bed"] = 1e6 * hi["step"] / hi["grains"]
    if len(rows) > 1:
        got["linearity, largest/smallest bed"] = (hi["step"] / hi["grains"]) / \
            (lo["step"] / lo["grains"])
    got["kB/grain, largest bed"] = hi["rss_per_grain"] / 1024
    log("")
    # 3. The 10^4-grain bed against LAMMPS
    from pdfem.tools.bench.peers import print_peers

    peers = print_peers(repeat, log=log)
    if "ratio" in peers:
        got["10^4 cap bed / LAMMPS disc-step, CPU"] = peers["ratio"]["cpu"]
    log("")
    # 4. Parallel overhead on 2 ranks
    par = _parallel(per_rank, repeat, log)
    if par is not None:
        got["parallel overhead %"] = 100 * par["overhead"]
    log("")
    # 5. Start-up
    st = print_startup(repeat, cold=cold, log=log)
    got["warm start s"] = st["warm"]
    log("")
    return summary(got, log)


def summary(got, log=print):
    """Print the closing table: figure, measured, target, met; return its rows."""
    log(f"{'figure':<38}{'measured':>10}{'target':>10}  met   (bench all, medians)")
    rows = []
    for name, target in TARGETS.items():
        if name not in got:
            log(f"{name:<38}{'-':>10}{target:>10g}  not measured")
            continue
        v = got[name]
        # Linearity is met within +-20 %, every other figure at or below its target
        ok = abs(v - 1.0) <= target - 1.0 if name.startswith("linearity") else v <= target
        rows.append((name, v, target, ok))
        log(f"{name:<38}{v:>10.2f}{target:>10g}  {'yes' if ok else 'NO'}")
    return rows
