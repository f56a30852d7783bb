"""Driven bodies that stop: velocity conditions with a release time.

A ``[[bc]]`` of type velocity on a block with ``release`` prescribes ``velocity`` until
``release - ramp_down``, then a velocity falling linearly to zero at ``release``, after which
the block's nodes are free: a piston that drives a bed at a steady speed, is brought to rest
and let go, so that what the bed does after the drive (spring back, stay compacted) is its
own. The prescribed value of a half step is the profile at the end of its interval, so the
last interval before the release brings the body exactly to rest; the reaction's work is
accounted by the integrator as for any velocity condition.
"""

import numpy as np


def factor(t, release, ramp):
    """Fraction of the prescribed velocity at time t (1 before the ramp, 0 from release)."""
    if t >= release:
        return 0.0
    if ramp > 0.0 and t > release - ramp:
        return (release - t) / ramp
    return 1.0


class Drives:
    """The velocity conditions of a run that have a release time (blocks only)."""

    def __init__(self, sim):
        blocks = sim.blocks
        self.items = []
        for bc in sim.resolved.get("bc", []):
            if "release" not in bc:
                continue
            dofs = np.array([c for c in range(2) if "xy"[c] in bc["dof"]], np.int64)
            self.items.append((blocks.gid(bc["body"]), blocks.nodes(bc["body"], bc["nodes"]),
                               dofs, np.asarray(bc["velocity"], float), bc["release"],
                               bc["ramp_down"]))

    def __len__(self):
        return len(self.items)

    def apply(self, sim, t0, t1):
        """Set the prescribed velocities of the half step from t0 to t1 (the profile at t1),
        or free the nodes when it starts at or after the release."""
        s = sim.store
        own = s.gid[: s.nb_own]
        for gid, local, dofs, vel, release, ramp in self.items:
            b = int(np.nonzero(own == gid)[0][0])
            nodes = s.nstart[b] + local
            for c in dofs:
                if t0 >= release:
                    s.bcf[nodes, c] = 0
                else:
                    s.bcv[nodes, c] = factor(t1, release, ramp) * vel[c]
