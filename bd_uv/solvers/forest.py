"""The number of connected components of a small graph counted by QDLDL's elimination tree
(``ordered_ldl``'s ``QDLDL_etree``): the elimination tree of a symmetric pattern is a forest of
one tree per connected component of its graph (``unwrapping.one_disk.find``: is the face graph
of a small disk one piece)."""
import numpy as np
from scipy.sparse import _sparsetools as _st

from . import ordered_ldl

# Up to this many vertices ``component_count`` counts the roots of the elimination tree; its
# walk costs the fill of the graph in its given order (``geometry.components`` above). A disk's
# face graph, us against ``components`` (least of 5 x 300): face:100 12 / 39 (faces shuffled:
# 19 / 41), lion-head:600 38 / 78 (shuffled 74 / 53), face:800 59 / 61 (shuffled 126 / 72).
FOREST_VERTICES = 500


def component_count(a, b, n):
    """The number of connected components of the graph on n vertices with edges (a[i], b[i])
    (int64 arrays), or None where the ordered factorisation cannot run or n is above
    FOREST_VERTICES. The elimination tree of a symmetric pattern is a forest of one tree per
    connected component of its graph, so its roots are counted (``QDLDL_etree`` of the upper
    pattern; repeated edges and loops are allowed): one compiled pass, ~12 us on a 115-face disk's
    face graph against ~40 us for ``geometry.components``' hooking rounds (``one_disk.find``
    needs the count alone)."""
    if not 0 < n <= FOREST_VERTICES or not ordered_ldl.available():
        return None
    # The entries (min, max) by column max (the rows of the transposed pairs' csr), and the
    # diagonal (``QDLDL_etree`` refuses an empty column).
    d = np.arange(n, dtype=np.int64)
    hi, lo = np.concatenate([np.maximum(a, b), d]), np.concatenate([np.minimum(a, b), d])
    k = len(hi)
    Ap, Ai = np.empty(n + 1, np.int64), np.empty(k, np.int64)
    _st.coo_tocsr(n, n, k, hi, lo, np.empty(k), Ap, Ai, np.empty(k))
    ints = np.empty(3 * n, np.int64)        # work, Lnz, etree
    at, p = ordered_ldl._p(ints), ordered_ldl._p
    if ordered_ldl._lib().QDLDL_etree(n, p(Ap), p(Ai), at, at + 8 * n, at + 16 * n) < 0:
        return None
    return int(np.count_nonzero(ints[2 * n:] < 0))
