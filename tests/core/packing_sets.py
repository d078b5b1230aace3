"""Random chart sets for the packer's tests, and independent checks of a packed layout.

Nothing here calls ``bd_uv``: gaps are brute-force segment-to-segment distances, densities and
turns are recomputed from the corners.
"""
import numpy as np
from scipy.spatial import cKDTree

RECT = (np.array([[0, 0], [1, 0], [1, 1], [0, 1]], float), np.array([[0, 1, 2], [0, 2, 3]]))


def annulus(inner=0.3):
    """A unit square with a square hole (8 triangles): a chart with a hole."""
    a, b = inner, 1 - inner
    P = np.array([[0, 0], [1, 0], [1, 1], [0, 1], [a, a], [b, a], [b, b], [a, b]], float)
    T = np.array([[0, 1, 5], [0, 5, 4], [1, 2, 6], [1, 6, 5], [2, 3, 7], [2, 7, 6], [3, 0, 4],
                  [3, 4, 7]])
    return P, T


def chart_set(kind, k, seed=0):
    """k charts of one kind: 'boxes', 'slivers', 'holes' or 'huge_tiny'.

    Each chart is a template stretched by (sx, sy); its 3D copy is scaled by a random factor (so
    densities differ before packing) and its UVs turned by a random angle and moved anywhere.

    Returns
    -------
    V (n,3), F (m,3), corner_uv (m,3,2), face_island (m,)
    """
    rng = np.random.default_rng(seed)
    P, T = annulus() if kind == "holes" else RECT
    size = rng.uniform(0.2, 1.0, (k, 2))
    if kind == "slivers":
        size[:, 0] *= 40
    if kind == "huge_tiny":
        size[1:] *= 0.05
        size[0] = (20.0, 14.0)
    Vs, Fs, uvs = [], [], []
    for i in range(k):
        local = P * size[i]
        Vs.append(np.c_[local * rng.uniform(0.5, 2.0), np.zeros(len(P))])
        th = rng.uniform(0, 2 * np.pi)
        R = np.array([[np.cos(th), -np.sin(th)], [np.sin(th), np.cos(th)]])
        uv = local @ R.T * rng.uniform(0.1, 3.0) + rng.uniform(-5, 5, 2)
        Fs.append(T + i * len(P))
        uvs.append(uv[T])
    return (np.concatenate(Vs), np.concatenate(Fs), np.concatenate(uvs),
            np.repeat(np.arange(k), len(T)))


def segment_distances(a0, a1, b0, b1):
    """Distances between segments a0-a1 and b0-b1 (rows), assumed not crossing: the least of the
    four point-to-segment distances."""
    def point_seg(p, s0, s1):
        d = s1 - s0
        t = np.clip(np.einsum("ij,ij->i", p - s0, d) / np.maximum(np.einsum("ij,ij->i", d, d),
                                                                     1e-300), 0, 1)
        return np.linalg.norm(p - (s0 + t[:, None] * d), axis=1)
    return np.minimum.reduce([point_seg(a0, b0, b1), point_seg(a1, b0, b1),
                              point_seg(b0, a0, a1), point_seg(b1, a0, a1)])


def least_gap(uv, lab, reach):
    """Least distance between triangle edges of two different charts, among edges whose midpoints
    are within ``reach`` plus their half lengths (a k-d tree on midpoints); inf if none. Exact
    when it is at most ``reach``; above, an upper bound (only nearby pairs are measured)."""
    e0 = uv.reshape(-1, 2)
    e1 = uv[:, [1, 2, 0]].reshape(-1, 2)
    el = np.repeat(lab, 3)
    # edges longer than a few median edges cut into pieces of at most that length: the search
    # radius is twice the longest piece, and one huge island's edges (or a sliver's) set beside
    # thousands of tiny ones made every pair a candidate (24 GB at 5,000 islands); the least
    # distance between two edges is the least between their pieces
    length = np.linalg.norm(e1 - e0, axis=1)
    piece = max(4.0 * float(np.median(length)), float(reach), 1e-300)
    n = np.clip(np.ceil(length / piece), 1, None).astype(np.int64)
    if n.max() > 1:
        own = np.repeat(np.arange(len(e0)), n)
        t = np.arange(len(own)) - np.repeat(np.cumsum(n) - n, n)
        a, b = t / n[own], (t + 1) / n[own]
        d = e1 - e0
        e0, e1 = e0[own] + a[:, None] * d[own], np.where(
            (b == 1)[:, None], e1[own], e0[own] + b[:, None] * d[own])
        el = el[own]
    mid = 0.5 * (e0 + e1)
    half = 0.5 * np.linalg.norm(e1 - e0, axis=1).max()
    pairs = cKDTree(mid).query_pairs(2 * half + reach, output_type="ndarray")
    pairs = pairs[el[pairs[:, 0]] != el[pairs[:, 1]]]
    if not len(pairs):
        return np.inf
    i, j = pairs.T
    return float(segment_distances(e0[i], e1[i], e0[j], e1[j]).min())


def chart_maps(uv_in, uv_out):
    """Per face, the 2x2 map taking the input corner edges to the output ones: (m,2,2)."""
    Ein = np.stack([uv_in[:, 1] - uv_in[:, 0], uv_in[:, 2] - uv_in[:, 0]], axis=2)
    Eout = np.stack([uv_out[:, 1] - uv_out[:, 0], uv_out[:, 2] - uv_out[:, 0]], axis=2)
    return Eout @ np.linalg.inv(Ein)


def texel_densities(V, F, uv, lab):
    """sqrt(UV area / 3D area) per chart."""
    def area(P):
        e1, e2 = P[:, 1] - P[:, 0], P[:, 2] - P[:, 0]
        return 0.5 * np.abs(e1[:, 0] * e2[:, 1] - e1[:, 1] * e2[:, 0])
    P3 = V[F]
    a3 = 0.5 * np.linalg.norm(np.cross(P3[:, 1] - P3[:, 0], P3[:, 2] - P3[:, 0]), axis=1)
    return np.sqrt(np.bincount(lab, area(uv)) / np.bincount(lab, a3))
