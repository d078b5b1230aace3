"""The Fiedler vectors of charts' dual graphs: the smooth ordering of each chart's faces that a
split sweeps (``split.fiedler_split_many``).

Each chart's vector is found by inverse iteration on the block-diagonal Laplacian of all the
charts of a batch (one sparse factorisation), started from the faces' coordinate along the
chart's longest principal axis; charts above ``cluster_fiedler.COARSE_NODES`` nodes get theirs
from a graph of clusters of their nodes (``cluster_fiedler.coarse_fiedler``).
"""
import functools

import numpy as np
import scipy.sparse as sp

from ..solvers.threads import halves, map_blocks, map_queue
from .charts import spd_solver
from . import cluster_fiedler
from .compressed import compressed
from .orders import fiedler_solver
from ..array_calls import einsum

# Charts of one batch are split into two systems factored side by side when each holds at
# least this many nodes.
PARALLEL_NODES = 1500
# ... but a batch of more nodes than this is factored in runs of charts of at most RUN_NODES
# nodes together, two runs side by side: two halves of a 286k-node batch side by side were
# the seam search's memory peak on a 500k-face mesh (~396 MB).
SEQUENTIAL_NODES = 120_000
RUN_NODES = 60_000


def fiedler_vectors(pairs, w, mass, centroid, offsets, group, iters=12, coarsen=True, keys=None):
    """``_fiedler_block`` of all charts; two runs of charts factor side by side when each is
    large enough (``solvers.threads``; each chart's vector is its own either way), a batch of
    more than ``SEQUENTIAL_NODES`` nodes in runs of at most ``RUN_NODES``, two at a time.
    Charts above ``cluster_fiedler.COARSE_NODES`` nodes get theirs from a graph of clusters of
    their nodes (``cluster_fiedler.coarse_fiedler``, where ``keys`` are not used)."""
    if coarsen and (np.diff(offsets) > cluster_fiedler.COARSE_NODES).any():
        def again(*a, coarsen):
            return fiedler_vectors(*a, iters=iters, coarsen=coarsen)
        return cluster_fiedler.coarse_fiedler(pairs, w, mass, centroid, offsets, group, again)
    g = len(offsets) - 1
    if len(mass) > SEQUENTIAL_NODES:
        cuts = _runs(np.diff(offsets), RUN_NODES)
    else:
        j = halves(np.diff(offsets), PARALLEL_NODES)
        if j is None:
            return _fiedler_block(pairs, w, mass, centroid, offsets, group, iters, keys)
        cuts = [0, j, g]
    # The run of each pair (both its nodes are in one chart, so in one run).
    which = (offsets[cuts[1:-1]]).searchsorted(pairs[:, 0], side="right")

    def run(i):
        a, b = cuts[i], cuts[i + 1]
        lo, hi = int(offsets[a]), int(offsets[b])
        sel = which == i
        return _fiedler_block(pairs[sel] - lo, w[sel], mass[lo:hi], centroid[lo:hi],
                              offsets[a:b + 1] - lo, group[lo:hi] - a, iters,
                              None if keys is None else keys[lo:hi])
    if len(cuts) == 3:
        xs = map_blocks(run, [0, 1])
    else:                                   # two runs at a time
        xs = map_queue(run, range(len(cuts) - 1), [False] * (len(cuts) - 1))
    if any(x is None for x in xs):
        return None
    return np.concatenate(xs)


def _runs(sizes, limit):
    """The first chart of each run of consecutive charts of ``sizes`` nodes holding at most
    ``limit`` together (a larger chart alone), and ``len(sizes)``."""
    cuts, total = [0], 0
    for j, s in enumerate(sizes.tolist()):
        if j > cuts[-1] and total + s > limit:
            cuts.append(j)
            total = 0
        total += s
    return cuts + [len(sizes)]


def _fiedler_block(pairs, w, mass, centroid, offsets, group, iters=12, keys=None):
    """Approximate Fiedler vectors of ``L x = lambda M x``, each chart's own, by inverse
    iteration on the block-diagonal Laplacian (one sparse factorisation for all charts).

    Each chart starts from its faces' coordinate along its principal axis (already a smooth
    ordering along its longest extent) plus a small fixed perturbation, and is deflated of
    its constant vector (M-orthogonally) each step; a dozen steps are enough for a sweep cut.

    Parameters
    ----------
    pairs : (e,2) int64, w : (e,) float64, the graph's edges and weights (Laplacian L)
    mass : (k,) float64 > 0, centroid : (k,3) float64
    offsets : (g+1,) int64, group : (k,) int64, the chart of each node
    keys : (k,) int64, optional: factor in their order (``orders.fiedler_solver``)

    Returns
    -------
    x : (k,) float64, or None when the system cannot be factored
    """
    g, k = len(offsets) - 1, len(mass)
    total = np.bincount(group, mass, g)
    mean = np.stack([np.bincount(group, mass * centroid[:, i], g) for i in range(3)], 1)
    c = centroid - (mean / np.maximum(total, 1e-300)[:, None])[group]
    axes = _principal_axes(c, mass, offsets, group)
    x = einsum("ij,ij->i", c, axes.take(group, axis=0))
    scale = np.zeros(g)
    np.maximum.at(scale, group, np.abs(x))
    noise = np.concatenate([_noise(int(n)) if n <= 5000 else
                            np.random.default_rng(int(n)).standard_normal(int(n))
                            for n in np.diff(offsets)])
    x = x + 1e-3 * np.maximum(scale, 1e-300)[group] * noise
    deg = np.bincount(pairs.ravel(), np.repeat(w, 2), minlength=k)
    cnt = np.maximum(np.bincount(group, minlength=g), 1)
    shift = 1e-8 * (np.bincount(group, deg, g) / cnt) / np.maximum(total / cnt, 1e-300)
    idx = np.arange(k)
    # Upper triangle only (the factorisation reads no more), as triplets: the ordered factor
    # sorts them in its own order (``orders.fiedler_solver``); compressed where needed.
    # (``np.minimum`` of the two columns, not ``pairs.min(axis=1)``: numpy's reduction along a
    # length-2 axis is ~30x slower, 0.2 ms on a 15k-pair chart, twice per batch)
    rows = np.concatenate([np.minimum(pairs[:, 0], pairs[:, 1]), idx])
    cols = np.concatenate([np.maximum(pairs[:, 0], pairs[:, 1]), idx])
    vals = np.concatenate([-w, deg + shift[group] * mass])

    def upper():
        return sp.csc_matrix(compressed(cols, rows, vals, k), shape=(k, k))
    try:
        if keys is None:            # (every system of a mesh above ``orders.MESH_VERTICES``)
            K = upper()
            rows = cols = vals = None       # not held beside the factor: only K, as before
            solve = spd_solver(K, upper=True)
        else:
            solve = fiedler_solver(rows, cols, vals, keys, upper)
    except RuntimeError:
        return None
    rows = cols = vals = K = None
    # Each chart's mean divided out per chart, then spread over its nodes (the same quotients
    # as dividing per node: one division a chart, not one a node, each iteration)
    tot = np.maximum(total, 1e-300)
    for _ in range(iters):
        x = x - (np.bincount(group, mass * x, g) / tot)[group]
        x = solve(mass * x)
        x = x / np.maximum(np.sqrt(np.bincount(group, mass * x ** 2, g)), 1e-300)[group]
    return x - (np.bincount(group, mass * x, g) / tot)[group]


@functools.lru_cache(maxsize=512)
def _noise(n):
    """The fixed perturbation of an n-node chart's start vector (seeded by n, read-only; kept
    for the small charts, which come back in every round: at most 512 x 5000 values)."""
    x = np.random.default_rng(n).standard_normal(n)
    x.flags.writeable = False
    return x


def _principal_axes(c, mass, offsets, group):
    """``_principal_axis`` of every chart at once (one batched eigen-decomposition); charts
    whose two largest moments tie go through ``_principal_axis`` one by one.

    Parameters
    ----------
    c : (k,3) float64, node centroids about their chart's weighted mean; mass : (k,) float64
    offsets : (g+1,) int64, group : (k,) int64, the chart of each node
    keys : (k,) int64, optional: factor in their order (``orders.fiedler_solver``)

    Returns
    -------
    (g,3) float64 unit axes ((1,0,0) for an empty chart)
    """
    g = len(offsets) - 1
    cov = np.empty((g, 3, 3))
    for a in range(3):
        for b in range(a, 3):
            cov[:, a, b] = cov[:, b, a] = np.bincount(group, mass * c[:, a] * c[:, b], g)
    w, vec = np.linalg.eigh(cov)
    axes = vec[:, :, 2].copy()
    proj = einsum("ij,ij->i", c, axes.take(group, axis=0))
    big = np.zeros(g)
    np.maximum.at(big, group, np.abs(proj))
    on = (np.abs(proj) > 1e-9 * big[group]).ravel().nonzero()[0]
    gon = group[on]
    if len(gon) and (np.diff(gon) >= 0).all():    # grouped chart by chart (every caller):
        first = on[np.r_[True, gon[1:] != gon[:-1]]]   # each chart's first, without a sort
    else:
        first = on[np.unique(gon, return_index=True)[1]]
    flip = np.zeros(g, dtype=bool)
    flip[group[first]] = proj[first] < 0
    axes[flip] *= -1
    size = np.diff(offsets)
    axes[size == 0] = (1.0, 0.0, 0.0)
    for j in ((w[:, 1] >= w[:, 2] * (1.0 - 1e-6)) & (size > 0)).ravel().nonzero()[0]:
        axes[j] = _principal_axis(c[offsets[j]:offsets[j + 1]], mass[offsets[j]:offsets[j + 1]])
    return axes


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
    first = (np.abs(c @ axis) > 1e-9 * np.abs(c @ axis).max(initial=0.0)).ravel().nonzero()[0]
    if len(first) and c[first[0]] @ axis < 0:
        axis = -axis
    return axis
