"""Fiedler vectors of large charts from a graph of clusters (the seam search on 100k+ faces).

A chart of more than ``COARSE_NODES`` nodes is split by the Fiedler vector of a graph of small
connected clusters of its nodes (the nodes of one grid cell, about ``CLUSTER`` of them, split
into their connected pieces so no cluster joins two sides of a thin part), prolonged to the
nodes and smoothed by a few averaging steps. The sweep and the min-cut snap that follow
(``split.fiedler_split_many``) run on the nodes as before: the cut still runs along the cheapest
edges within a band around the coarse cut. What it saves is the factorisation of the node
Laplacian (as large as the chart's LSCM system), a third of the search's time on a 500k-face
mesh; the cluster graph has ~16 times fewer nodes (again coarsened while still above the limit).
"""
import numpy as np
import scipy.sparse as sp
from scipy.sparse.csgraph import connected_components

# Charts with more nodes than this get their Fiedler vector from the cluster graph. Not lower:
# measured (load ~11, one run each) at 20k, armadillo (52k faces) got 45 charts instead of 41
# and horse (97k) 42 instead of 34, both already far within xatlas's time; at 5k-10k, fandisk's
# creases blur (3 charts -> 4-6, seams +7-20 %). dino subdivided twice (125k faces): 52 -> 49
# charts, seams -1 %, 10 % less time.
COARSE_NODES = 50_000
# Nodes per cluster, about (the grid cell holds this much of the chart's mean node area).
CLUSTER = 16
# Averaging steps smoothing the prolonged vector (piecewise constant on the clusters).
SMOOTH = 6
# (chart, cell) keys below this bound are formed as mixed-radix integers, larger ones as
# dense ranks (``clusters``).
KEY_LIMIT = 1 << 62


def clusters(mass, centroid, pairs, group, g):
    """Cluster of every node: a node of a chart of at most ``COARSE_NODES`` nodes alone, the
    others by grid cell (side ``sqrt(CLUSTER * mean node area)`` of their chart), each cell's
    nodes split into their connected pieces.

    Parameters
    ----------
    mass : (k,) float64, centroid : (k,3) float64, pairs : (e,2) int64 (within charts)
    group : (k,) int64 nondecreasing, chart of each node; g : int charts

    Returns
    -------
    label : (k,) int32, clusters numbered by their smallest node (so grouped chart by chart)
    coarse : (k,) bool, the nodes of the charts that are coarsened
    """
    k = len(mass)
    size = np.bincount(group, minlength=g)
    big = size > COARSE_NODES
    coarse = big[group]
    h = np.sqrt(CLUSTER * np.bincount(group, mass, g) / np.maximum(size, 1))
    with np.errstate(invalid="ignore", divide="ignore"):
        q = np.floor(centroid / np.maximum(h, 1e-300)[group][:, None])
    q = np.where(coarse[:, None] & np.isfinite(q), q, 0).astype(np.int64)
    # Each chart's lowest cell (group is nondecreasing: each chart's nodes are one run, so a
    # ``reduceat`` over the runs gives ``np.minimum.at``'s values, ~10x faster).
    start = np.searchsorted(group, np.arange(g))
    low = np.zeros((g, 3), np.int64)
    held = size > 0
    if held.any():
        low[held] = np.minimum.reduceat(q, start[held], axis=0)
    q -= low[group]                         # cells counted from each chart's corner
    # One key per (chart, cell), a node of a small chart its own (negative) key. Only which
    # nodes share a key matters (the clusters are the components of the pairs within a key,
    # numbered by scipy by their smallest node): the mixed-radix key of (chart, cell) where it
    # is below ``KEY_LIMIT`` (no sort), else dense ranks built an axis at a time (``np.unique``).
    span = [int(q[:, d].max(initial=0)) + 1 for d in range(3)]
    if g * span[0] * span[1] * span[2] < KEY_LIMIT:
        key = group.astype(np.int64) * span[0] + q[:, 0]
        key = (key * span[1] + q[:, 1]) * span[2] + q[:, 2]
    else:
        key = group
        for d in range(3):
            _, key = np.unique(key * span[d] + q[:, d], return_inverse=True)
            key = key.ravel()
    key = np.where(coarse, key, -1 - np.arange(k))
    same = key[pairs[:, 0]] == key[pairs[:, 1]]
    gr = sp.csr_matrix((np.ones(int(same.sum())), (pairs[same, 0], pairs[same, 1])), shape=(k, k))
    _, label = connected_components(gr, directed=False)
    # int32 (scipy's own labels): they index the pairs (``coarse_fiedler``'s (e,2) cluster
    # pairs of a 500k-face chart: 11 MB in int64, copied once more).
    return label.astype(np.int32, copy=False), coarse


def coarse_fiedler(pairs, w, mass, centroid, offsets, group, fiedler):
    """Fiedler vectors as ``fiedler(pairs, w, mass, centroid, offsets, group)`` gives them, the
    charts above ``COARSE_NODES`` nodes through their cluster graph (``clusters``).

    Returns
    -------
    (k,) float64 or None (as ``fiedler``)
    """
    g = len(offsets) - 1
    label, coarse = clusters(mass, centroid, pairs, group, g)
    nc = int(label.max()) + 1
    cmass = np.bincount(label, mass, nc)
    ccen = np.stack([np.bincount(label, mass * centroid[:, d], nc) for d in range(3)], 1)
    ccen /= np.maximum(cmass, 1e-300)[:, None]
    cgroup = np.zeros(nc, dtype=np.int64)
    cgroup[label] = group
    cp = label[pairs]
    across = cp[:, 0] != cp[:, 1]
    coffsets = np.searchsorted(cgroup, np.arange(g + 1))
    # Coarsened again while that still halves the largest chart.
    again = 2 * np.diff(coffsets).max(initial=0) <= np.diff(offsets).max(initial=0)
    xc = fiedler(cp[across], w[across], cmass, ccen, coffsets, cgroup, coarsen=bool(again))
    if xc is None:
        return None
    x = xc[label]
    # Averaging over the neighbours (weights w), on the coarsened charts' nodes only.
    p0, p1 = pairs[:, 0], pairs[:, 1]
    deg = np.bincount(p0, w, len(x)) + np.bincount(p1, w, len(x))
    on = coarse & (deg > 0)
    for _ in range(SMOOTH):
        avg = (np.bincount(p0, w * x[p1], len(x)) + np.bincount(p1, w * x[p0], len(x)))
        x = np.where(on, 0.5 * x + 0.5 * avg / np.where(on, deg, 1.0), x)
    return x
