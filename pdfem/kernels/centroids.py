"""Body centroids: the mean node position of each body of a store."""

from numba import njit


@njit(cache=True)
def body_centroids(x, nstart, nn, b0, b1, out):
    """Mean node position of bodies [b0, b1), summed in node order."""
    for b in range(b0, b1):
        sx = 0.0
        sy = 0.0
        for i in range(nstart[b], nstart[b] + nn[b]):
            sx += x[i, 0]
            sy += x[i, 1]
        out[b - b0, 0] = sx / nn[b]
        out[b - b0, 1] = sy / nn[b]
