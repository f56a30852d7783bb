"""Wall time per phase of the step, with min/avg/max across ranks in the run report.

Phases nest: time spent in a phase opened inside another counts for the inner one only (the
outer is paused meanwhile), so the phases add up to the time measured.
"""

import time
from contextlib import contextmanager

import numpy as np

from pdfem.parallel.mpi import allgather_objects

# contact_exchange: the grain-block contact rows gathered from every rank, with the wait for
# the slowest rank to reach that point of the step
PHASES = ("elements", "contact_detection", "contact_forces", "contact_exchange", "halo",
          "migration", "heat", "integration", "diagnostics", "output")


class Timers:
    """Accumulated seconds per phase and a count of kernel calls per phase."""

    def __init__(self):
        self.seconds = dict.fromkeys(PHASES, 0.0)
        self.calls = dict.fromkeys(PHASES, 0)
        # The open phases, innermost last: [name, time its current stretch began]
        self._open = []

    @contextmanager
    def phase(self, name):
        """Time the enclosed block under ``name`` (an enclosing phase is paused)."""
        t0 = time.perf_counter()
        if self._open:
            outer = self._open[-1]
            self.seconds[outer[0]] += t0 - outer[1]
        self._open.append([name, t0])
        try:
            yield
        finally:
            t1 = time.perf_counter()
            _, start = self._open.pop()
            self.seconds[name] += t1 - start
            self.calls[name] += 1
            if self._open:
                self._open[-1][1] = t1

    def report(self, comm):
        """{phase: (min, avg, max) seconds across ranks}, same on every rank."""
        local = np.array([self.seconds[p] for p in PHASES])
        allv = np.array(allgather_objects(comm, local))
        return {p: (allv[:, i].min(), allv[:, i].mean(), allv[:, i].max())
                for i, p in enumerate(PHASES)}

    def imbalance(self, comm):
        """Max over mean of the ranks' busy time (every phase but output and the contact
        exchange, which holds the wait for the other ranks): 1 is perfect."""
        busy = sum(v for k, v in self.seconds.items() if k not in ("output", "contact_exchange"))
        allv = np.array(allgather_objects(comm, busy))
        return float(allv.max() / allv.mean()) if allv.mean() > 0 else 1.0
