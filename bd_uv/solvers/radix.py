"""Stable sort orders of bounded non-negative integer keys by numpy's radix sort.

numpy sorts 16-bit integers stably by radix (linear time) but 64-bit ones by timsort or
quicksort: on the seam search's keys (vertex pairs of a chart, entries of a sparse matrix,
chart labels; 10k-100k of them, hundreds of sorts a call) a sort was 1-4 ms where two 16-bit
passes take 0.1-0.4 ms. The orders are ``np.argsort(key, kind="stable")``'s exactly (a stable
order is unique), so nothing sorted this way changes.
"""
import numpy as np

DIGIT = 1 << 16
# Keys above this many go to numpy's own sort (``np.unique``): the passes hold a few more
# key-sized arrays at once, and on a 500k-face mesh the Fiedler sweep over every face and the
# LSCM assembly of the largest charts are memory peaks (+11 MB measured), while their sorts are
# a small share of those steps' time.
LARGE = 1 << 18


def order(key, bound, passes=2):
    """``np.argsort(key, kind="stable")`` of integer keys in ``[0, bound)``: one 16-bit radix
    pass per 16 bits of ``bound`` (least significant first) while at most ``passes`` (up to 4)
    do, numpy's stable sort beyond (and for more than ``LARGE`` keys)."""
    key = np.asarray(key)
    if len(key) > LARGE:
        return key.argsort(kind="stable")
    if bound <= DIGIT:
        return key.astype(np.uint16).argsort(kind="stable")
    need = 1
    while need < 4 and bound > 1 << (16 * need):
        need += 1
    if need > passes or bound > 1 << 63:
        return key.argsort(kind="stable")
    o = (key & (DIGIT - 1)).astype(np.uint16).argsort(kind="stable")
    for d in range(1, need):
        o = o[((key[o] >> (16 * d)) & (DIGIT - 1)).astype(np.uint16).argsort(kind="stable")]
    return o


def unique(key, bound):
    """``np.unique(key, return_inverse=True, return_counts=True)`` of integer keys in
    ``[0, bound)`` (1-D), sorted by ``order``."""
    key = np.asarray(key)
    if len(key) > LARGE:
        u, inv, counts = np.unique(key, return_inverse=True, return_counts=True)
        return u, inv.ravel(), counts
    o = order(key, bound)
    s = key[o]
    first = np.ones(len(s), dtype=bool)
    first[1:] = s[1:] != s[:-1]
    starts = first.ravel().nonzero()[0]
    inv = np.empty(len(s), dtype=np.intp)
    inv[o] = first.cumsum() - 1
    return s[starts], inv, np.diff(np.append(starts, len(s)))
