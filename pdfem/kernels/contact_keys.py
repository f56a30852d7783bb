"""Global keys of candidate contacts, and the merge of two key-sorted candidate lists.

A candidate is an element pair (a, b) (local element indices, a of lower global key) or an
element-wall pair (e, -1 - w). Its key is (gid_a, elem_a, gid_b, elem_b), a wall's
(gid, elem, -1 - w, 0): the order in which contact forces are added to a node on every rank.
A third column, where present, is the pair's period shift k (periodic sides: b is met k box
widths to the right; 0 otherwise), which is not part of the key.
"""

from numba import njit


@njit(cache=True)
def candidate_key(cand, c, egid, eloc):
    """Global contact key of candidate c of cand (n, 2)."""
    a = cand[c, 0]
    b = cand[c, 1]
    if b >= 0:
        return egid[a], eloc[a], egid[b], eloc[b]
    return egid[a], eloc[a], b, 0


@njit(cache=True)
def key_less(h0, h1, h2, h3, k0, k1, k2, k3):
    """(h0, h1, h2, h3) < (k0, k1, k2, k3) lexicographically."""
    if h0 != k0:
        return h0 < k0
    if h1 != k1:
        return h1 < k1
    if h2 != k2:
        return h2 < k2
    return h3 < k3


@njit(cache=True)
def _key_le(c1, i, c2, j, egid, eloc):
    """key(c1[i]) <= key(c2[j])."""
    a0, a1, a2, a3 = candidate_key(c1, i, egid, eloc)
    b0, b1, b2, b3 = candidate_key(c2, j, egid, eloc)
    return not key_less(b0, b1, b2, b3, a0, a1, a2, a3)


@njit(cache=True)
def merge_candidates(c1, c2, egid, eloc, out):
    """Merge two key-sorted candidate lists into out (n1 + n2, ncol), c1's first on equal keys
    (every column of a row copied: the pair and its shift)."""
    i = 0
    j = 0
    n1 = c1.shape[0]
    n2 = c2.shape[0]
    for k in range(n1 + n2):
        if j >= n2 or (i < n1 and _key_le(c1, i, c2, j, egid, eloc)):
            for col in range(out.shape[1]):
                out[k, col] = c1[i, col]
            i += 1
        else:
            for col in range(out.shape[1]):
                out[k, col] = c2[j, col]
            j += 1
