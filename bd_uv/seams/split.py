"""Splitting a chart in two along its cheapest neck (spectral bisection with a Cheeger sweep)."""
import numpy as np
import scipy.sparse as sp
from scipy.sparse.csgraph import breadth_first_order, connected_components, maximum_flow

from .charts import spd_solver

# Neither side of a split may hold less than this share of the chart's area.
MIN_SIDE = 0.05
# Dual rings on each side of a sweep cut within which the min cut may move it.
BAND_RINGS = 4


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
    x = _fiedler_vector(pairs, w, face_area, centroid)
    if x is None:
        return None
    # Rounded (then by face): the order, and so the cut, does not hang on the last bits of
    # x, which differ between runs with the memory layout (BLAS kernels).
    order = np.lexsort((np.arange(k), _quantize(x)))
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
    t = int(np.argmin(_quantize(score))) + 1
    side = rank < t
    side = _snap(side, pairs, c)
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


def _fiedler_vector(pairs, w, mass, centroid, iters=12):
    """Approximate Fiedler vector of ``L x = lambda M x`` by inverse iteration.

    Starts from the faces' coordinate along the chart's principal axis (already a smooth
    ordering along its longest extent), deflates the constant vector (M-orthogonally) each step;
    a dozen steps with one sparse factorisation are enough for a sweep cut.

    Parameters
    ----------
    pairs : (e,2) int64, w : (e,) float64, the graph's edges and weights (Laplacian L)
    mass : (k,) float64 > 0
    centroid : (k,3) float64

    Returns
    -------
    x : (k,) float64, or None when the system cannot be factored
    """
    c = centroid - np.average(centroid, axis=0, weights=mass)
    k = len(mass)
    x = c @ _principal_axis(c, mass)
    # A small fixed perturbation (the same for the same chart): on a symmetric chart the
    # Fiedler vector is not unique, and inverse iteration would otherwise pick a direction
    # out of the rounding noise.
    x = x + 1e-3 * max(np.abs(x).max(), 1e-300) * np.random.default_rng(k).standard_normal(k)
    deg = np.bincount(pairs.ravel(), np.repeat(w, 2), minlength=k)   # pairs.ravel(): row-major
    shift = 1e-8 * deg.mean() / mass.mean()
    # L + shift M from triplets in one go: off-diagonal -w, diagonal degree + shift * mass.
    idx = np.arange(k)
    K = sp.csc_matrix((np.concatenate([-w, -w, deg + shift * mass]),
                       (np.concatenate([pairs[:, 0], pairs[:, 1], idx]),
                        np.concatenate([pairs[:, 1], pairs[:, 0], idx]))), shape=(k, k))
    try:
        solve = spd_solver(K)
    except RuntimeError:
        return None
    total = mass.sum()
    for _ in range(iters):
        x = x - (mass @ x) / total
        x = solve(mass * x)
        x /= max(np.sqrt(mass @ x ** 2), 1e-300)
    return x - (mass @ x) / total


def _principal_axis(c, mass):
    """The chart's longest principal axis, chosen the same way in every run.

    Where the two (or three) largest principal moments agree to 1e-6 (a chart symmetric about
    an axis) the axis is any direction of their plane and an SVD returns one picked by rounding
    noise: then take the first face's direction projected onto that plane.

    Parameters
    ----------
    c : (k,3) float64, face centroids about their weighted mean; mass : (k,) float64

    Returns
    -------
    (3,) float64, unit axis, oriented so the first face lies on its non-negative side
    """
    cov = (c * mass[:, None]).T @ c
    w, vec = np.linalg.eigh(cov)
    w, vec = w[::-1], vec[:, ::-1]
    top = w >= w[0] * (1.0 - 1e-6)
    axis = vec[:, 0]
    if top.sum() > 1:
        span = vec[:, top]
        for f in range(len(c)):           # the first face off the plane's normal
            a = span @ (span.T @ c[f])
            if np.linalg.norm(a) > 1e-6 * np.sqrt(max(w[0], 1e-300) / mass.sum()):
                axis = a / np.linalg.norm(a)
                break
    first = np.flatnonzero(np.abs(c @ axis) > 1e-9 * np.abs(c @ axis).max(initial=0.0))
    if len(first) and c[first[0]] @ axis < 0:
        axis = -axis
    return axis


def _quantize(x, digits=9):
    """``x`` rounded to ``10**-digits`` of its largest finite magnitude (ties then broken by
    index, the same in every run)."""
    x = np.asarray(x, dtype=np.float64)
    fin = np.isfinite(x)
    scale = np.abs(x[fin]).max(initial=0.0)
    if scale == 0:
        return x
    q = scale * 10.0 ** -digits
    return np.where(fin, np.round(x / q) * q, x)


def _snap(side, pairs, cost, rings=BAND_RINGS):
    """Move a two-way cut to the cheapest one within a band of faces around it (s-t min cut).

    The faces more than ``rings`` dual steps from the cut keep their side (they are the source
    and the sink); inside the band the cut is free, so it runs along creases (cheap edges) and
    takes the shortest route, straight where the mesh has a straight edge loop, rather than the
    level set's staircase.

    Parameters
    ----------
    side : (k,) bool
    pairs : (e,2) int64, neighbouring faces
    cost : (e,) float64 > 0, the seam cost of each shared edge (length times crease discount)

    Returns
    -------
    (k,) bool
    """
    k = len(side)
    A = sp.coo_array((np.ones(2 * len(pairs)), (np.concatenate([pairs[:, 0], pairs[:, 1]]),
                                                np.concatenate([pairs[:, 1], pairs[:, 0]]))),
                     shape=(k, k)).tocsr()
    across = side[pairs[:, 0]] != side[pairs[:, 1]]
    band = np.zeros(k, dtype=bool)
    band[pairs[across].ravel()] = True
    for _ in range(rings):
        band |= (A @ band.astype(np.float64)) > 0
    if band.all():
        return side
    # Graph: faces 0..k-1, source k (side True outside the band), sink k+1.
    scale = 1e4 / max(cost.max(), 1e-300)    # integer capacities, sums within int32
    cap = np.maximum(np.round(cost * scale), 1).astype(np.int64)
    src_f = np.flatnonzero(~band & side)
    snk_f = np.flatnonzero(~band & ~side)
    if len(src_f) == 0 or len(snk_f) == 0:
        return side
    inf = min(int(cap.sum()) + 1, 2 ** 30)
    rows = np.concatenate([pairs[:, 0], pairs[:, 1], np.full(len(src_f), k), snk_f])
    cols = np.concatenate([pairs[:, 1], pairs[:, 0], src_f, np.full(len(snk_f), k + 1)])
    vals = np.concatenate([cap, cap, np.full(len(src_f), inf), np.full(len(snk_f), inf)])
    G = sp.csr_matrix(sp.coo_array((vals, (rows, cols)), shape=(k + 2, k + 2)))
    G.sum_duplicates()
    G.data = np.minimum(G.data, 2 ** 30).astype(np.int32)
    flow = maximum_flow(G, k, k + 1).flow
    residual = (G - flow).tocsr()
    residual.data = (residual.data > 0).astype(np.float64)
    residual.eliminate_zeros()
    reach = breadth_first_order(residual, k, directed=True, return_predecessors=False)
    new = np.zeros(k + 2, dtype=bool)
    new[reach] = True
    return new[:k]
