"""Theorems 5.1 and 5.2's premises checked on a map (Lipman 2012, section 5).

An orientation-preserving piecewise-linear map that takes the boundary of a disk (or of a domain
with holes) one-to-one onto a simple polygon (a domain with as many holes) is a bijection onto it.
``bijectivity_premises`` checks both on the map's own vertex positions.
"""
from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class BijectivityPremises:
    """Theorems 5.1/5.2's premises checked on a map.

    Attributes
    ----------
    orientation_preserving : bool, every face's image has positive signed area
    boundary_simple : bool, the outer image loop is a simple counter-clockwise polygon, every hole
        loop a simple clockwise polygon inside it, and no two loops touch or nest wrongly
    bijective : bool, both (the map is then a bijection onto the polygon's domain)
    message : str, what failed ("" when bijective)
    """
    orientation_preserving: bool
    boundary_simple: bool
    bijective: bool
    message: str


def oriented_loop(tris, loop):
    """The loop in the direction of its faces' edges, so the faces lie on its left.

    Parameters
    ----------
    tris : (k,3) int, loop : (b,) int

    Returns
    -------
    (b,) int64
    """
    loop = np.asarray(loop, dtype=np.int64)
    E = np.concatenate([tris[:, [0, 1]], tris[:, [1, 2]], tris[:, [2, 0]]])
    n = int(tris.max()) + 1
    keys = np.sort(E[:, 0] * n + E[:, 1])
    k = loop[0] * n + loop[1]
    pos = np.searchsorted(keys, k)
    forward = pos < len(keys) and keys[pos] == k
    return loop if forward else loop[::-1].copy()


def _cross(a, b):
    return a[..., 0] * b[..., 1] - a[..., 1] * b[..., 0]


def _segments_cross(P, Q, Pn, Qn):
    """Closed segments P-Pn and Q-Qn intersect (touching counts), for stacked pairs."""
    d1, d2 = Pn - P, Qn - Q
    o1, o2 = _cross(d1, Q - P), _cross(d1, Qn - P)
    o3, o4 = _cross(d2, P - Q), _cross(d2, Pn - Q)
    proper = (o1 * o2 <= 0) & (o3 * o4 <= 0)
    colinear = (o1 == 0) & (o2 == 0)
    lo1, hi1 = np.minimum(P, Pn), np.maximum(P, Pn)
    lo2, hi2 = np.minimum(Q, Qn), np.maximum(Q, Qn)
    overlap = np.all((lo1 <= hi2) & (lo2 <= hi1), axis=-1)
    return np.where(colinear, overlap, proper & overlap)


def _signed_area(X):
    return 0.5 * np.sum(_cross(X, np.roll(X, -1, axis=0)))


def _inside(pt, X):
    """Point strictly inside polygon X (even-odd rule)."""
    a, b = X, np.roll(X, -1, axis=0)
    up = (a[:, 1] <= pt[1]) != (b[:, 1] <= pt[1])
    with np.errstate(divide="ignore", invalid="ignore"):
        x = a[:, 0] + (pt[1] - a[:, 1]) * (b[:, 0] - a[:, 0]) / (b[:, 1] - a[:, 1])
    return bool(np.sum(up & (x > pt[0])) % 2)


def bijectivity_premises(uv, tris, loops):
    """Check Theorem 5.1/5.2's premises on a map: orientation-preserving, simple target boundary.

    Parameters
    ----------
    uv : (nv,2) float, the map's vertex positions
    tris : (k,3) int
    loops : sequence of (b,) int boundary loops (the one with the largest image area is outer)

    Returns
    -------
    BijectivityPremises
    """
    uv = np.asarray(uv, dtype=np.float64)
    tris = np.asarray(tris, dtype=np.int64)
    T = uv[tris]
    e1, e2 = T[:, 1] - T[:, 0], T[:, 2] - T[:, 0]
    n_bad = int(np.sum(~(_cross(e1, e2) > 0)))
    orient = n_bad == 0
    rings = [uv[oriented_loop(tris, lp)] for lp in loops]
    areas = np.array([_signed_area(X) for X in rings])
    outer = int(np.argmax(areas))
    msgs = [] if orient else [f"{n_bad} face(s) flipped or collapsed"]
    simple = bool(areas[outer] > 0) and all(areas[i] < 0 for i in range(len(rings)) if i != outer)
    if not simple:
        msgs.append("a boundary loop runs the wrong way round")
    # No two boundary edges meet except consecutive ones at their shared vertex.
    P = np.concatenate(rings)
    Pn = np.concatenate([np.roll(X, -1, axis=0) for X in rings])
    ring = np.repeat(np.arange(len(rings)), [len(X) for X in rings])
    pos = np.concatenate([np.arange(len(X)) for X in rings])
    size = np.array([len(X) for X in rings])[ring]
    i, j = np.triu_indices(len(P), 1)
    same = ring[i] == ring[j]
    adjacent = same & ((pos[j] - pos[i] == 1) | (pos[j] - pos[i] == size[i] - 1))
    hit = _segments_cross(P[i], P[j], Pn[i], Pn[j]) & ~adjacent
    # Consecutive edges meet only at their shared vertex: not folded back onto each other.
    offset = np.concatenate([[0], np.cumsum([len(X) for X in rings])[:-1]])
    nxt = offset[ring] + (pos + 1) % size
    d_in, d_out = Pn - P, Pn[nxt] - P[nxt]
    folded = (_cross(d_in, d_out) == 0) & (np.einsum("ij,ij->i", d_in, d_out) <= 0)
    if hit.any() or folded.any():
        simple = False
        msgs.append(f"the boundary image touches or crosses itself ({int(hit.sum())} edge pair(s))")
    for h in range(len(rings)):
        if h != outer and not _inside(rings[h][0], rings[outer]):
            simple = False
            msgs.append(f"hole {h} lies outside the outer boundary")
        for g in range(len(rings)):
            if g not in (h, outer) and h != outer and _inside(rings[h][0], rings[g]):
                simple = False
                msgs.append(f"hole {h} lies inside hole {g}")
    return BijectivityPremises(orient, simple, orient and simple, "; ".join(msgs))
