"""The per-step halo refresh: owner values of node arrays copied into the ghosts.

Between rebuilds (:func:`pdfem.parallel.exchange.rebuild`, which makes the plan) only node
positions and velocities (and the fields effects register) of ghosts change, from owner to
ghost, every step: one non-blocking send per neighbour rank, one receive per ghost source.
"""

import numpy as np
from mpi4py import MPI


class Halo:
    """Per-step owner -> ghost refresh plan: node indices to send, ghost slices to fill."""

    def __init__(self, comm, send, recv):
        self.comm = comm
        self.send = send  # {rank: local node indices, in the order the receiver stores them}
        self.recv = recv  # {rank: (first ghost node, count)}

    def refresh(self, arrays):
        """Copy owner values of the given node arrays into the ghosts (x, v, ...)."""
        comm = self.comm
        reqs, rbufs = [], {}
        width = sum(int(np.prod(a.shape[1:])) for a in arrays)
        for r, (_, cnt) in self.recv.items():
            rbufs[r] = np.empty(cnt * width, np.float64)
            reqs.append(comm.Irecv(rbufs[r], source=r, tag=7))
        sbufs = []
        for r, idx in self.send.items():
            buf = np.concatenate([a[idx].reshape(idx.shape[0], -1) for a in arrays], axis=1)
            sbufs.append(np.ascontiguousarray(buf).ravel())
            reqs.append(comm.Isend(sbufs[-1], dest=r, tag=7))
        MPI.Request.Waitall(reqs)
        for r, (n0, cnt) in self.recv.items():
            buf = rbufs[r].reshape(cnt, -1)
            col = 0
            for a in arrays:
                w = int(np.prod(a.shape[1:]))
                a[n0 : n0 + cnt] = buf[:, col : col + w].reshape((cnt,) + a.shape[1:])
                col += w
