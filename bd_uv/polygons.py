"""Polygons triangulated for the solve, in face-vertex ids.

A polygon keeps its fan from its first corner where no fan triangle turns against the polygon
or has no area (every convex polygon, every planar quad that is not concave: the triangles solved
so far). Where one does not, the fan from the first other corner whose fan does (an n-gon whose
straight side holds three corners, as dissolving edges leaves: Rhino's ``wallhole.obj``), else
the polygon is ear-clipped in its plane (a concave polygon: Houdini's glyphs), so no triangle
lies outside its polygon or has no area where a triangulation without that exists: a fan
triangle outside a concave polygon overlaps its neighbour in the UV map, one with no area has no
distortion to certify.
"""
import functools

import numpy as np

# A fan triangle lies outside its polygon (a concave corner) when its area about the Newell
# normal is below -FLAT of the polygon's. A fan triangle outside is flattened folded open across
# its diagonal, its corner mirrored, and the polygons beside it bend to meet it: negligible at
# the 1e-6 a bent quad of a curved grid turns a corner against its plane, whole units of
# distortion on Houdini's glyphs. Corners on a line are left to ``_no_area``'s 3D test.
FLAT = 1e-3
# ``mesh.arrays.DEGENERATE_RATIO``, the unwrap's own test of a face with no area (a layer above,
# so not imported; tests/core/test_polygons.py holds them equal).
DEGENERATE_RATIO = 1e-12
# A polygon whose corners lie farther than PLANAR times the square root of its area from its
# plane is bent, not concave: a fan triangle turning against its normal is a fold of the surface
# the fan from its first corner makes (as other readers make it), kept.
PLANAR = 0.01
# Ear clipping looks at every remaining corner for each ear: polygons of more corners keep
# their fan (none such has been met; a cap keeps a damaged file's huge polygon from taking
# minutes).
MAX_CLIPPED = 4096


def fan_triangles(counts):
    """Fan triangulation of polygons, in face-vertex ids.

    Parameters
    ----------
    counts : (p,) int array, vertices of each polygon (>= 3)

    Returns
    -------
    T : (m,3) int64 face-vertex ids (into the polygons' corner list), polygon j's triangles
        (s, s+i, s+i+1) for i = 1 .. counts[j]-2, s its first face-vertex
    poly : (m,) int64 polygon of each triangle
    """
    counts = np.asarray(counts, dtype=np.int64)
    start = np.concatenate([[0], np.cumsum(counts)[:-1]])
    ntri = counts - 2
    poly = np.repeat(np.arange(len(counts)), ntri)
    i = np.arange(len(poly)) - np.repeat(np.cumsum(ntri) - ntri, ntri) + 1
    s = start[poly]
    return np.stack([s, s + i, s + i + 1], 1), poly


def triangulate(V, counts, corners, precision=None):
    """Each polygon's triangles: its fan where that is sound, else its ears.

    Parameters
    ----------
    V : (n,3) float array, the points
    counts : (p,) int array, corners of each polygon (>= 3)
    corners : (sum(counts),) int array, each polygon's corners in order (ids into ``V``)
    precision : float type the points were stored in, optional (``np.float32``: a USD stage's,
        which the scene unwrap measures faces at): a triangle that precision cannot tell from
        a line has no area too, as ``repair.zero_area_faces`` finds it

    Returns
    -------
    T : (m,3) int64 face-vertex ids (into ``corners``), each polygon's ``count - 2`` triangles
        in its rows of :func:`fan_triangles`, wound as the polygon is
    poly : (m,) int64 polygon of each triangle
    clipped : (k,) int64 the polygons not fanned from their first corner (that fan was not
        sound): fanned from another, or ear-clipped
    """
    counts = np.asarray(counts, dtype=np.int64)
    T, poly = fan_triangles(counts)
    clipped = np.zeros(0, np.int64)
    if not len(counts) or counts.max() < 4:
        return T, poly, clipped
    P = np.asarray(V, dtype=np.float64)[np.asarray(corners, dtype=np.int64)]
    start = np.concatenate([[0], np.cumsum(counts)[:-1]])
    owner = np.repeat(np.arange(len(counts)), counts)
    nxt = np.arange(len(P)) + 1
    nxt[start + counts - 1] = start
    normal = np.zeros((len(counts), 3))
    np.add.at(normal, owner, np.cross(P, P[nxt]))      # Newell: twice the area, along the normal
    a = P[T[:, 0]]
    u, w = P[T[:, 1]] - a, P[T[:, 2]] - a
    cr = np.cross(u, w)                                 # each fan triangle's, once
    turn = np.einsum("ij,ij->i", cr, normal[poly])
    size = np.einsum("ij,ij->i", normal, normal)
    # concave, and flat enough that this is a corner inside-out, not a polygon bent in space
    # (a quad of a curved grid: its fan is what other readers take, and as sound a surface)
    with np.errstate(all="ignore"):
        unit = normal / np.sqrt(size)[:, None]
        height = np.abs(np.einsum("ij,ij->i", P - P[start[owner]], unit[owner]))
        bent = np.maximum.reduceat(height, start) > PLANAR * np.sqrt(np.sqrt(size) / 2)
    unsound = (turn < -FLAT * size[poly]) & (counts[poly] >= 4) & ~bent[poly]
    # every triangle turning the right way, but the fan going round its first corner more than
    # once (a spiral about it): the fan's angles at that corner add up to over a full turn
    angle = np.arctan2(np.linalg.norm(cr, axis=1), np.einsum("ij,ij->i", u, w))
    sweep = np.bincount(poly, angle, len(counts))
    unsound |= (sweep[poly] >= 2 * np.pi - 1e-9) & (counts[poly] >= 4) & ~bent[poly]
    total = 0.0
    if precision is not None:           # the fans' area, for the UV step's test
        with np.errstate(all="ignore"):
            total = 0.5 * float(np.nansum(np.linalg.norm(cr, axis=1)))
    no_area = functools.partial(_no_area, precision=precision, total=total)
    unsound |= no_area(P[T]) & (counts[poly] >= 4)
    unsound &= size[poly] > 0          # corners all on a line (or not finite): the fan as it is
    clipped = np.unique(poly[unsound])
    clipped = clipped[counts[clipped] <= MAX_CLIPPED]
    for p in clipped.tolist():
        s, c = int(start[p]), int(counts[p])
        rows = slice(*np.searchsorted(poly, [p, p + 1]))   # poly is sorted
        T[rows] = s + _turned_fan_or_ears(P[s:s + c], normal[p], no_area)
    return T, poly, clipped


def _turned_fan_or_ears(Q, n, no_area):
    """(c-2,3) corner ids of the polygon ``Q`` (c,3), Newell normal ``n``, whose fan from its
    first corner is not sound: the fan from the first other corner whose fan is (an n-gon whose
    first three corners lie on a line: from its second; ``no_area``: ``_no_area`` at the
    points' precision), else its ears."""
    c = len(Q)
    j = np.arange(1, c - 1)
    size = float(n @ n)
    for r in range(1, c):
        fan = np.stack([np.full(c - 2, r), (r + j) % c, (r + j + 1) % c], 1)
        a = Q[fan[:, 0]]
        u, w = Q[fan[:, 1]] - a, Q[fan[:, 2]] - a
        turn = np.cross(u, w) @ n
        sweep = np.arctan2(np.linalg.norm(np.cross(u, w), axis=1), np.einsum("ij,ij->i", u, w))
        if (turn >= -FLAT * size).all() and sweep.sum() < 2 * np.pi - 1e-9 \
                and not no_area(Q[fan]).any():
            return fan
    return _ears(_in_plane(Q, n))


def _no_area(P, precision=None, total=0.0):
    """(m,) bool: triangles ``P`` (m,3,3) of finite corners with no area by the unwrap's own
    test (twice the area at most ``DEGENERATE_RATIO`` times the longest edge squared); with a
    ``precision`` other than float64, also those whose height (twice the area over the longest
    edge) is below one step of it at their largest coordinate, or one UV step of it (in the unit
    square's upper half) times the square root of the area ``total`` (``mesh.arrays``'
    ``thinner_than_precision``, a layer above: found by the polygon fuzz contract, a USD
    polygon's fan triangle over three corners in a line that float32 moved off it was kept,
    then refused by the unwrap as of no area)."""
    with np.errstate(all="ignore"):
        twice = np.linalg.norm(np.cross(P[:, 1] - P[:, 0], P[:, 2] - P[:, 0]), axis=1)
        longest = np.max(np.sum((P - np.roll(P, -1, axis=1)) ** 2, axis=2), axis=1)
        zero = ~(twice > DEGENERATE_RATIO * longest)
        if precision is not None and np.dtype(precision) != np.float64:
            step = np.spacing(np.abs(P).max(axis=(1, 2)).astype(precision)).astype(np.float64)
            uv_step = float(np.spacing(np.asarray(0.5, dtype=precision))) * np.sqrt(total)
            zero |= ~(twice > np.maximum(step, uv_step) * np.sqrt(longest))
        return zero & np.isfinite(P).all(axis=(1, 2))


def _in_plane(Q, n):
    """(c,2) the points ``Q`` in the plane normal to ``n``, turning counter-clockwise about it."""
    n = n / np.linalg.norm(n)
    u = np.cross(n, [1.0, 0.0, 0.0] if abs(n[0]) < 0.9 else [0.0, 1.0, 0.0])
    u /= np.linalg.norm(u)
    return np.column_stack([Q @ u, Q @ np.cross(n, u)])


def _ears(q):
    """(c-2,3) corner ids of the counter-clockwise polygon ``q`` (c,2) cut ear by ear.

    An ear is three consecutive remaining corners turning left with an area and holding no
    other remaining corner (closed, so a corner on its side counts; corners at one of its own
    points do not). Where none is left (a polygon crossing itself), the rest is fanned."""
    c = len(q)
    scale = np.abs(q - q.mean(0)).max() or 1.0
    q = (q - q.mean(0)) / scale
    eps = 1e-12
    ring = list(range(c))
    out = []
    k = 0
    misses = 0
    while len(ring) > 3 and misses < len(ring):
        m = len(ring)
        i0, i1, i2 = ring[(k - 1) % m], ring[k % m], ring[(k + 1) % m]
        a, b, d = q[i0], q[i1], q[i2]
        area = (b[0] - a[0]) * (d[1] - a[1]) - (b[1] - a[1]) * (d[0] - a[0])
        if area > eps and not _holds_any(q, [j for j in ring if j not in (i0, i1, i2)], a, b, d):
            out.append((i0, i1, i2))
            ring.pop(k % m)
            k = (k - 1) % (m - 1)       # the corner before the ear may be one now
            misses = 0
        else:
            k = (k + 1) % m
            misses += 1
    if len(ring) > 3:                   # no ear: fan the rest as it was
        out += [(ring[0], ring[j], ring[j + 1]) for j in range(1, len(ring) - 1)]
    else:
        out.append(tuple(ring))
    return np.asarray(out, dtype=np.int64)


def _holds_any(q, others, a, b, d):
    """True when the closed triangle (a, b, d) holds a point of ``q[others]`` other than its own
    three points."""
    if not others:
        return False
    p = q[others]
    at_corner = ((p == a).all(1) | (p == b).all(1) | (p == d).all(1))
    tol = -1e-12

    def side(u, v):
        return (v[0] - u[0]) * (p[:, 1] - u[1]) - (v[1] - u[1]) * (p[:, 0] - u[0])
    inside = (side(a, b) >= tol) & (side(b, d) >= tol) & (side(d, a) >= tol)
    return bool((inside & ~at_corner).any())
