"""Which corner each polygon of an OBJ is fanned from.

A polygon of n corners is cut into the n - 2 triangles of a fan from one of its corners. From the
first corner, as readers do, unless a triangle of that fan has no area (the corner on the line of
an edge not its own: an n-gon whose straight side holds three corners, as dissolving edges
leaves), which the unwrap could only refuse; then from the first corner whose fan has none.
"""
import numpy as np

#: a triangle has no area when twice its area is at most this times its longest edge squared;
#: ``mesh.arrays.DEGENERATE_RATIO``, the unwrap's own test (a layer apart, so not imported;
#: ``tests/core/test_obj_patch.py`` holds them equal)
FLAT = 1e-12


def fan_corners(V, corner_v, starts):
    """Each triangle's polygon and its corners' places in the polygon.

    Parameters
    ----------
    V : (n,3) float array
    corner_v : (c,) int array, the vertex of each polygon corner (polygon p's at
        ``starts[p]:starts[p + 1]``, in the file's order), every one a row of ``V``
    starts : (P+1,) int array, the first corner of each polygon (each of 3 corners or more)

    Returns
    -------
    polygon : (m,) int64, the polygon of each triangle, polygon p's n - 2 triangles consecutive
    corners : (m,3) int64, each triangle's corners as places 0..n-1 in its polygon: triangle j of
        a fan from corner r is r, r + j + 1, r + j + 2 (mod n)
    """
    corner_v = np.asarray(corner_v, dtype=np.int64)
    starts = np.asarray(starts, dtype=np.int64)
    sizes = np.diff(starts)
    tris = sizes - 2
    polygon = np.repeat(np.arange(len(sizes)), tris)
    first = np.concatenate([[0], np.cumsum(tris)])[:-1]
    j = np.arange(len(polygon)) - first[polygon]
    corners = np.stack([np.zeros_like(j), j + 1, j + 2], axis=1)
    flat = _flat(V, corner_v[starts[polygon][:, None] + corners])
    for p in np.unique(polygon[flat]).tolist():   # only the polygons with such a triangle
        n, k = int(sizes[p]), int(first[p])
        fan = corners[k:k + n - 2]
        for r in range(1, n):
            turned = (fan + r) % n
            if not _flat(V, corner_v[starts[p] + turned]).any():
                corners[k:k + n - 2] = turned
                break
    return polygon, corners


def _flat(V, F):
    """(m,) bool: the triangles ``F`` of finite corners with no area (``FLAT``)."""
    P = np.asarray(V, dtype=np.float64)[F]
    with np.errstate(all="ignore"):
        twice = np.linalg.norm(np.cross(P[:, 1] - P[:, 0], P[:, 2] - P[:, 0]), axis=1)
        longest = np.max(np.sum((P - np.roll(P, -1, axis=1)) ** 2, axis=2), axis=1)
        return ~(twice > FLAT * longest) & np.isfinite(P).all(axis=(1, 2))
