"""Schedules in simulated time: output at the first step at or past each multiple of an
interval (frames, energy samples, gauge samples, checkpoints). SI units (seconds).

The scene checks (:mod:`pdfem.scene.schedules`) bound what an interval may imply; the index
of the next due multiple is found in constant time, so no interval, however small, makes a
step spin.
"""

import math

# A multiple k of the interval is due at t >= k interval (1 - SLACK): rounding of t never
# skips one
SLACK = 1e-12


def next_index(k, interval, t):
    """The smallest index j >= k with j interval (1 - SLACK) > t (interval > 0)."""
    # Start below the answer (the quotient's rounding is off by less than one), then step
    # with the due test's own expression
    j = max(k, math.floor(t / (interval * (1 - SLACK))) - 1)
    while j * interval * (1 - SLACK) <= t:
        j += 1
    return j


class Schedule:
    """Output at the first step at or past each multiple of an interval (exact times are
    stored with the data; steps are never shortened to land on them)."""

    def __init__(self, interval):
        self.interval, self.k = interval, 1

    def due(self, t):
        """True (once) when t has reached the next multiple of the interval."""
        if t < self.k * self.interval * (1 - SLACK):
            return False
        self.k = next_index(self.k, self.interval, t)
        return True
