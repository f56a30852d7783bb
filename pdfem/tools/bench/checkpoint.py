"""``pdfem bench checkpoint``: what a checkpoint costs, in time and in rank 0's memory.

Run under mpirun (or alone: one rank). The bed is the benchmark bed of pdfem.tools.bench.beds
(cap grains, 6 elements each, contact history after a few steps) with ``grains`` grains,
split in strips. After the warm-up steps the checkpoint is written ``repeat`` times; then a
restart reads it back, ``repeat`` times.

Figures, per rank: the seconds of the write and of the restart's set-up (median; the
slowest rank), the file's size, and the growth of the resident set during the write and
during the restart over what the rank held just before (Linux: the peak resident size is
reset through ``/proc/self/clear_refs`` and read from ``VmHWM``). Printed on rank 0.
"""

import os
import statistics
import tempfile
import time

import numpy as np

from pdfem.parallel.mpi import barrier, broadcast, global_max, global_sum, world
from pdfem.tools.bench.contact import reset_peak, rss_bytes
from pdfem.tools.bench.elements import machine
from pdfem.tools.bench.parallel import bed_simulation

# Warm-up steps before the first checkpoint (contact history builds up)
WARMUP = 3


def _measured(comm, action):
    """Run action() on every rank; (slowest rank's seconds, this rank's peak growth in
    bytes over its resident size before)."""
    barrier(comm)
    reset_peak()
    before = rss_bytes("VmRSS")
    t0 = time.perf_counter()
    action()
    wall = time.perf_counter() - t0
    peak = rss_bytes("VmHWM")
    return global_max(comm, wall), peak - before


def _state(nterm):
    """A driver state as a run's first checkpoint has it (no frames, no energy rows yet) for a
    run of nterm energy terms."""
    return {"nframe": 0, "frames_k": 1, "samples_k": 1, "gauges_k": 1, "checkpoint_k": 1,
            "run_file": "", "segments": [],
            "arrays": {"energy_rows": np.zeros((0, nterm + 3)), "energy_ref": np.zeros(nterm)}}


def run_checkpoint(grains, repeat, comm=None):
    """Write and read back a checkpoint of a ``grains``-grain bed; a dict of figures (rank 0:
    its own memory; times of the slowest rank)."""
    from pdfem.io.checkpoint import write_checkpoint
    from pdfem.solver import Simulation

    comm = comm or world()
    sim = bed_simulation(comm, grains)
    for _ in range(WARMUP):
        sim.step()
    folder = broadcast(comm, tempfile.mkdtemp(prefix="pdfem-bench-") if comm.rank == 0 else None)
    path = os.path.join(folder, "bench.ckpt.h5")
    resident = rss_bytes("VmRSS")
    state = _state(len(sim.terms))
    writes = [_measured(comm, lambda: write_checkpoint(path, sim.state, sim.ctx, state))
              for _ in range(repeat)]
    size = os.path.getsize(path)
    scene, fields = sim.scene, sim.fields
    nhist = global_sum(comm, sim.store.hkey.shape[0])
    sim = None  # freed before the restarts

    # The restart's whole set-up: the scene's bodies, then the checkpoint's in their place
    def restart():
        Simulation(scene, comm, restart=path)

    reads = [_measured(comm, restart) for _ in range(repeat)]
    if comm.rank == 0:
        os.remove(path)
        os.rmdir(folder)
    return {"ranks": comm.size, "grains": grains, "fields": len(fields), "history": nhist,
            "bytes": size, "resident": resident,
            "write": statistics.median(w[0] for w in writes),
            "write_peak": max(w[1] for w in writes),
            "restart": statistics.median(r[0] for r in reads),
            "restart_peak": max(r[1] for r in reads)}


def print_checkpoint(grains, repeat, log=print):
    """Run the checkpoint benchmark; print its figures on rank 0; return the dict."""
    comm = world()
    r = run_checkpoint(grains, repeat, comm)
    if comm.rank != 0:
        return r
    mib = 2.0**20
    log(f"pdfem bench checkpoint: {r['grains']} cap grains (6 elements each) on {r['ranks']} "
        f"ranks, {r['history']} contact history rows, median of {repeat} samples; times of "
        "the slowest rank, memory of rank 0")
    log(machine().replace("one core", f"{r['ranks']} ranks"))
    log(f"checkpoint file {r['bytes'] / mib:.1f} MiB; rank 0 resident {r['resident'] / mib:.0f}"
        f" MiB before the write")
    log(f"write {r['write']:.3f} s; rank 0 peak growth during the write "
        f"{r['write_peak'] / mib:.1f} MiB")
    log(f"restart set-up {r['restart']:.3f} s; rank 0 peak growth during it "
        f"{r['restart_peak'] / mib:.1f} MiB")
    return r
