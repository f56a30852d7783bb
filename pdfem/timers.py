"""Wall time per phase of the step, with min/avg/max across ranks in the run report."""

import time
from contextlib import contextmanager

import numpy as np

from pdfem.parallel.mpi import allgather_objects

PHASES = ("elements", "contact_detection", "contact_forces", "halo", "migration", "heat",
          "integration", "diagnostics", "output")


class Timers:
    """Accumulated seconds per phase and a count of kernel calls per phase."""

    def __init__(self):
        self.seconds = dict.fromkeys(PHASES, 0.0)
        self.calls = dict.fromkeys(PHASES, 0)

    @contextmanager
    def phase(self, name):
        """Time the enclosed block under ``name``."""
        t0 = time.perf_counter()
        try:
            yield
        finally:
            self.seconds[name] += time.perf_counter() - t0
            self.calls[name] += 1

    def report(self, comm):
        """{phase: (min, avg, max) seconds across ranks}, same on every rank."""
        local = np.array([self.seconds[p] for p in PHASES])
        allv = np.array(allgather_objects(comm, local))
        return {p: (allv[:, i].min(), allv[:, i].mean(), allv[:, i].max())
                for i, p in enumerate(PHASES)}

    def imbalance(self, comm):
        """Max over mean of the ranks' busy time (every phase but output): 1 is perfect."""
        busy = sum(v for k, v in self.seconds.items() if k != "output")
        allv = np.array(allgather_objects(comm, busy))
        return float(allv.max() / allv.mean()) if allv.mean() > 0 else 1.0
