"""Splitting a chart in two along its cheapest neck (spectral bisection with a Cheeger sweep)."""
import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla
from scipy.sparse.csgraph import connected_components

# Neither side of a split may hold less than this share of the chart's area.
MIN_SIDE = 0.05


def fiedler_split(face_area, centroid, pairs, edge_len, edge_cost):
    """Two-way split of a chart's faces along a cheap, short, straight cut.

    The Fiedler vector of the chart's dual graph (edge weights ``length * cost / centroid
    distance``, face areas as mass) orders the faces smoothly along the chart's longest extent;
    the sweep then picks the prefix whose cut weight per area of the smaller side
    (``sum(length * cost) / min(A1, A2)``, the Cheeger ratio) is least, which falls on necks and
    creases. A majority filter then moves every face with two of its three neighbours on the
    other side across, which turns staircases into straight runs along edge loops.

    Parameters
    ----------
    face_area : (k,) float64
    centroid : (k,3) float64
    pairs : (e,2) int64, chart-local face pairs sharing an edge that may be cut
    edge_len, edge_cost : (e,) float64, length and seam cost of each such edge

    Returns
    -------
    side : (k,) bool, or None when the chart cannot be split
    """
    k = len(face_area)
    if k < 2 or len(pairs) == 0:
        return None
    d = np.linalg.norm(centroid[pairs[:, 0]] - centroid[pairs[:, 1]], axis=1)
    w = edge_len * edge_cost / np.maximum(d, 1e-12 * edge_len.mean())
    W = sp.coo_array((np.concatenate([w, w]), (np.concatenate([pairs[:, 0], pairs[:, 1]]),
                                               np.concatenate([pairs[:, 1], pairs[:, 0]]))),
                     shape=(k, k)).tocsc()
    L = (sp.diags(np.asarray(W.sum(axis=1)).ravel()) - W).tocsc()
    x = _fiedler_vector(L, face_area, centroid)
    if x is None:
        return None
    order = np.argsort(x, kind="stable")
    rank = np.empty(k, dtype=np.int64)
    rank[order] = np.arange(k)
    lo = np.minimum(rank[pairs[:, 0]], rank[pairs[:, 1]])
    hi = np.maximum(rank[pairs[:, 0]], rank[pairs[:, 1]])
    # Edge (f,g) is cut by prefixes of t faces with lo < t <= hi.
    c = edge_len * edge_cost
    diff = np.bincount(lo + 1, c, minlength=k + 1) - np.bincount(hi + 1, c, minlength=k + 1)
    cut = np.cumsum(diff)[1:k]                 # prefixes of 1..k-1 faces
    A = np.cumsum(face_area[order])[:-1]
    total = face_area.sum()
    small = np.minimum(A, total - A)
    score = np.where(small >= MIN_SIDE * total, cut / np.maximum(small, 1e-300), np.inf)
    if not np.isfinite(score).any():
        score = cut / np.maximum(small, 1e-300)
    t = int(np.argmin(score)) + 1
    side = rank < t
    raw = side.copy()
    # Majority filter: a face with two or three neighbours across moves over (never two
    # neighbours at once, which could leave a checkerboard), a few passes.
    for _ in range(4):
        other = side[pairs[:, 0]] != side[pairs[:, 1]]
        move = np.bincount(pairs[other].ravel(), minlength=k) >= 2
        both = move[pairs[:, 0]] & move[pairs[:, 1]]
        move[np.maximum(pairs[both, 0], pairs[both, 1])] = False
        if not move.any():
            break
        side = side ^ move
    # Pieces cut off from their side's bulk (a few faces) go to the other side.
    same = side[pairs[:, 0]] == side[pairs[:, 1]]
    g = sp.coo_array((np.ones(int(same.sum())), (pairs[same, 0], pairs[same, 1])), shape=(k, k))
    _, comp = connected_components(g, directed=False)
    size = np.bincount(comp)
    side = side ^ (size[comp] < max(3, 0.02 * k))
    if side.all() or not side.any():
        side = raw
    return side


def _fiedler_vector(L, mass, centroid, iters=12):
    """Approximate Fiedler vector of ``L x = lambda M x`` by inverse iteration.

    Starts from the faces' coordinate along the chart's principal axis (already a smooth
    ordering along its longest extent), deflates the constant vector (M-orthogonally) each step;
    a dozen steps with one sparse factorisation are enough for a sweep cut.

    Parameters
    ----------
    L : (k,k) sparse graph Laplacian
    mass : (k,) float64 > 0
    centroid : (k,3) float64

    Returns
    -------
    x : (k,) float64, or None when the system cannot be factored
    """
    c = centroid - np.average(centroid, axis=0, weights=mass)
    _, _, vt = np.linalg.svd(c * np.sqrt(mass)[:, None], full_matrices=False)
    x = c @ vt[0]
    shift = 1e-8 * L.diagonal().mean() / mass.mean()
    try:
        lu = spla.splu((L + sp.diags(shift * mass)).tocsc(), permc_spec="MMD_AT_PLUS_A",
                       options={"SymmetricMode": True})
    except RuntimeError:
        return None
    total = mass.sum()
    for _ in range(iters):
        x = x - (mass @ x) / total
        x = lu.solve(mass * x)
        x /= max(np.sqrt(mass @ x ** 2), 1e-300)
    return x - (mass @ x) / total
