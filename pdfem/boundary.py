"""The scene's boundary conditions, ``[[bc]]``, read once: :class:`BoundaryConditions`.

A condition holds a node set of a block (``body`` and ``nodes``: pdfem.setup.Blocks) or every
node lying on a side of the domain at t = 0 (``wall``). ``fixed`` holds both components at
rest; ``velocity`` prescribes the components of ``dof`` (the nodes start with that velocity:
an impulsive start, booked by the integrator as the condition's work). Each node carries the
flags bcf (0 free, 1 fixed, 2 prescribed) and the prescribed values bcv; the integrator reads
them every step.

A velocity condition on a block with ``release`` prescribes ``velocity`` until
``release - ramp_down``, then a velocity falling linearly to zero at ``release``, after which
the block's nodes are free: a piston that drives a bed at a steady speed, is brought to rest
and let go, so that what the bed does after the drive (spring back, stay compacted) is its
own. The prescribed value of a half step is the profile at the end of its interval, so the
last interval before the release brings the body exactly to rest; the reaction's work is
accounted by the integrator as for any velocity condition.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any, Protocol

import numpy as np

if TYPE_CHECKING:
    from pdfem.store import Batch, Store


class Blocks(Protocol):
    """What the conditions ask of the blocks (pdfem.setup.Blocks, which imports this
    module)."""

    names: list[str]

    def index(self, name: str) -> int: ...

    def gid(self, name: str) -> int: ...

    def nodes(self, name: str, which: str = "all") -> np.ndarray: ...


def factor(t: float, release: float, ramp: float) -> float:
    """Fraction of the prescribed velocity at time t (1 before the ramp, 0 from release)."""
    if t >= release:
        return 0.0
    if ramp > 0.0 and t > release - ramp:
        return (release - t) / ramp
    return 1.0


def _dof_mask(dof: str) -> np.ndarray:
    return np.array(["x" in dof, "y" in dof])


class BoundaryConditions:
    """The resolved ``[[bc]]`` list of a run with the domain's box and its blocks: the flags
    and values of the first state's nodes (:meth:`set_on_blocks`, :meth:`set_on_grains`)
    and the release schedule of the releasing conditions (:meth:`apply`)."""

    def __init__(self, bcs: list[dict[str, Any]], box: list[float], blocks: Blocks) -> None:
        self.bcs, self.box, self.blocks = list(bcs), box, blocks
        # The conditions with a release time (blocks only): body gid, block-local nodes,
        # components, velocity, release time, ramp
        self.releases: list[tuple[int, np.ndarray, np.ndarray, np.ndarray, float, float]] = []
        for bc in self.bcs:
            if "release" not in bc:
                continue
            dofs = np.array([c for c in range(2) if "xy"[c] in bc["dof"]], np.int64)
            self.releases.append((blocks.gid(bc["body"]), blocks.nodes(bc["body"], bc["nodes"]),
                                  dofs, np.asarray(bc["velocity"], float), bc["release"],
                                  bc["ramp_down"]))

    def set_on_blocks(self, batch: Batch, first: np.ndarray) -> None:
        """Flags, values and starting velocities of the blocks' nodes (a batch of every
        block, block i's first node at first[i]): every condition."""
        self._set(batch, self.bcs, first)

    def set_on_grains(self, batch: Batch) -> None:
        """The same for a batch of grains: the wall conditions only."""
        self._set(batch, [bc for bc in self.bcs if "wall" in bc], None)

    def _set(self, batch: Batch, bcs: list[dict[str, Any]], first: np.ndarray | None) -> None:
        x, bcf, bcv, v = batch.a["x"], batch.a["bcf"], batch.a["bcv"], batch.a["v"]
        box = self.box
        tol = 1e-9 * max(box[2] - box[0], box[3] - box[1])
        for bc in bcs:
            # Select the nodes of this condition
            if "body" in bc:
                assert first is not None, "a block condition on a batch without blocks"
                name = bc["body"]
                nodes = self.blocks.nodes(name, bc.get("nodes", "all")) + first[
                    self.blocks.index(name)]
            else:
                coord = {"left": (0, box[0]), "right": (0, box[2]), "bottom": (1, box[1]),
                         "top": (1, box[3])}[bc["wall"]]
                nodes = np.nonzero(np.abs(x[:, coord[0]] - coord[1]) <= tol)[0]
            # Constrain the chosen components
            kind = bc["type"]
            mask = _dof_mask("xy" if kind == "fixed" else bc["dof"])
            for k in range(2):
                if mask[k]:
                    bcf[nodes, k] = 2 if kind == "velocity" else 1
                    if kind == "velocity":
                        bcv[nodes, k] = bc["velocity"][k]
                        v[nodes, k] = bc["velocity"][k]

    def apply(self, store: Store, t0: float, t1: float) -> None:
        """Set the prescribed velocities of the half step from t0 to t1 (the profile at t1),
        or free the nodes when it starts at or after the release."""
        s = store
        own = s.gid[: s.nb_own]
        for gid, local, dofs, vel, release, ramp in self.releases:
            b = int(np.nonzero(own == gid)[0][0])
            nodes = s.nstart[b] + local
            for c in dofs:
                if t0 >= release:
                    s.bcf[nodes, c] = 0
                else:
                    s.bcv[nodes, c] = factor(t1, release, ramp) * vel[c]
