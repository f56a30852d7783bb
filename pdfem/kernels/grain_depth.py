"""How deep each node of a body lies below the body's boundary: the potential law's field.

The potential contact law (contact_potential) integrates over an overlap the potential of the
element it lies in. Were that potential the element's own, zero on every edge of the element,
a node that crossed a grain's boundary elements into its interior ones would be pushed towards
the nearest edge of the element it sits in, deeper as often as not, and the grains would pass
into each other. The potential is therefore the body's: a piecewise-linear field that is zero
on the body's boundary and rises towards its inside, element by element,

    psi = D_i at corner i,    D_i = l_i u,

with l_i the number of element edges between node i and the body's boundary (0 on it) and u
the mean contact length ``elen`` of the body's boundary elements as built (a fixed length, so
that psi is a function of the positions only and the forces are an energy's gradient). At an
element's centroid psi is the larger of the corners' mean and half the element's contact length:
an element with every corner on the boundary keeps the report-era element potential (zero on
its edges, elen / 2 at its centroid), and so does the outer triangle of every boundary element.

The layers come from the body's own connectivity and contact lengths, so every rank gets the
same bits for a body, ghost or owned.
"""

import numpy as np
from numba import njit


@njit(cache=True)
def element_depths(conn, ebnd, elen, estart, ne, nstart, nn, edep, eapex):
    """Corner values edep (ne, 4) and centroid values eapex (ne,) of the potential of every
    element of every body (body b: elements [estart[b], estart[b] + ne[b]), nodes [nstart[b],
    nstart[b] + nn[b]) of conn (ne, 4) rank-local node ids); ebnd (ne, 4) boundary-edge
    flags, elen (ne,) contact lengths."""
    big = np.iinfo(np.int64).max // 2
    layer = np.empty(max(1, nn.max()) if nn.shape[0] else 1, np.int64)
    for b in range(estart.shape[0]):
        e0 = estart[b]
        e1 = e0 + ne[b]
        n0 = nstart[b]
        for i in range(nn[b]):
            layer[i] = big
        # Boundary nodes (on a boundary edge) are layer 0; the unit is their elements' mean
        # contact length
        total = 0.0
        count = 0
        for e in range(e0, e1):
            edge = False
            for k in range(4):
                if ebnd[e, k] != 0:
                    edge = True
                    layer[conn[e, k] - n0] = 0
                    layer[conn[e, (k + 1) & 3] - n0] = 0
            if edge and elen[e] > 0.0:
                total += elen[e]
                count += 1
        unit = total / count if count else 0.0
        # Layers by relaxation along element edges, until none changes
        changed = True
        while changed:
            changed = False
            for e in range(e0, e1):
                for k in range(4):
                    i = conn[e, k] - n0
                    j = conn[e, (k + 1) & 3] - n0
                    if layer[i] + 1 < layer[j]:
                        layer[j] = layer[i] + 1
                        changed = True
                    elif layer[j] + 1 < layer[i]:
                        layer[i] = layer[j] + 1
                        changed = True
        # Corner values, and the centroid's: half an element deeper than the shallowest
        # corner (half its own contact length for an element with one), or the corners' mean
        for e in range(e0, e1):
            mean = 0.0
            low = np.inf
            for k in range(4):
                lk = layer[conn[e, k] - n0]
                edep[e, k] = lk * unit if lk < big else 0.0
                mean += edep[e, k]
                low = min(low, edep[e, k])
            half = 0.5 * (elen[e] if elen[e] > 0.0 else unit)
            eapex[e] = max(low + half, 0.25 * mean)
