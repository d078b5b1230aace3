"""The certificate of one disk's UVs as stored, in one pass (``one_disk``): what
``certificate.certify_islands`` measures of a one-island layout, cleared without its general
machinery, or None for it to measure and word.

The mesh is known to be one clean disk (``one_disk.find``): each interior edge's two half-edges
are known, and its boundary half-edges in order along the one loop. From the corner UVs as stored:

1. every face's Jacobian (``metrics.face_jacobians``' arithmetic on the faces' gradient
   operators), its conformal distortion and signed UV area; no face flipped or collapsed, the max
   within the bound (``certificate.RTOL``);
2. the UV boundary (``uv_boundary.uv_boundary``): an interior edge's two half-edges must carry the same
   UVs at both ends, so the boundary segments are the loop's, and each must end where the next
   starts: one closed polygon;
3. the polygon is simple (``overlap.island_overlaps``, Lipman 2012, Theorems 5.1-5.2): no UV point
   twice (no pinch), no two consecutive segments folding back onto each other, no two others
   meeting (their candidates by a sweep over x, decided by ``segments.segments_meet``'s robust
   predicates), and it winds counter-clockwise (the faces' side has winding number 1).
A failure of any step is left to ``certify_islands`` (and the unwrap's ``overlap_certificate``,
which cuts an overlapping island), so its reasons are worded in one place.
"""
import numpy as np

from ..certificate import RTOL, Certificate
from ..array_calls import einsum, quiet
from ..segments import segments_meet


def certify_disk(corner_uv, G, disk, C, rtol=RTOL):
    """Certify the UVs of a ``one_disk.Disk`` at the bound C.

    Parameters
    ----------
    corner_uv : (m,3,2) float64, the UVs as stored
    G : (m,2,3) float64, each face's gradient operator (``geometry.gradient_operators``)
    disk : one_disk.Disk

    Returns
    -------
    (Certificate, D (m,) each face's conformal distortion, the least and the largest singular
    value over the faces), or (None, D, nan, nan) when a step fails (``certify_islands`` decides)
    """
    D, smin, smax = measure_disk(corner_uv, G)
    cert = certify_measured_disk(corner_uv, D, disk, C, rtol)
    if cert is None:
        return None, D, np.nan, np.nan
    return cert, D, smin, smax


def measure_disk(corner_uv, G):
    """Step 1's measures of the UVs (m,3,2) as stored, with each face's gradient operator G
    (m,2,3): (D (m,) each face's conformal distortion, inf where a face flips or collapses; the
    least and the largest singular value over the faces)."""
    d = corner_uv - corner_uv[:, :1]
    gx = einsum("mkc,mc->mk", G, d[:, :, 0])
    gy = einsum("mkc,mc->mk", G, d[:, :, 1])
    alpha = 0.5 * ((gx[:, 0] + gy[:, 1]) + 1j * (gy[:, 0] - gx[:, 1]))
    beta = 0.5 * ((gx[:, 0] - gy[:, 1]) + 1j * (gy[:, 0] + gx[:, 1]))
    a, b = np.abs(alpha), np.abs(beta)
    # ``metrics._distortion(a, b, ~(signed_uv_areas(corner_uv) > 0))``, its arithmetic written
    # here (the corners' edges are d's rows 1 and 2): the same bits without its np.errstate
    # (~2-4 us) and two calls
    e1, e2 = d[:, 1], d[:, 2]
    flipped = ~(0.5 * (e1[:, 0] * e2[:, 1] - e1[:, 1] * e2[:, 0]) > 0)
    with quiet("invalid", "divide"):
        D = (a + b) / (a - b)
    D[~(a > b) | ~np.isfinite(D) | flipped] = np.inf
    return D, float(np.minimum.reduce(a - b)), float(np.maximum.reduce(a + b))


def certify_measured_disk(corner_uv, D, disk, C, rtol=RTOL):
    """``certify_disk``'s Certificate (or None) where each face's distortion D (m,) of these
    very UVs is known: measured by ``metrics.certify_measured`` from them (``finish``), the same
    arithmetic and the same bits as step 1's (the faces' frames from the same edges). Steps 1's
    bound, 2 and 3 are checked here as ever."""
    m = len(corner_uv)
    mx = float(np.maximum.reduce(D))
    if not (mx <= C * (1.0 + rtol) and np.logical_and.reduce(np.isfinite(corner_uv), axis=None)):
        return None
    if not _simple_ccw_boundary(corner_uv, disk):
        return None
    # the area-weighted mean as certify_islands sums it (bincount's order: the same bits)
    one = np.zeros(m, dtype=np.int64)
    area = np.bincount(one, disk.area, 1)[0]
    mean = np.bincount(one, disk.area * D, 1)[0] / area
    return Certificate(island=0, certified=True, bound=float(C), max_distortion=mx,
                       mean_distortion=float(mean), flipped=0, overlap_free=True, crossings=0,
                       reason="", faces=m, area=float(area))


def _simple_ccw_boundary(corner_uv, disk):
    """Steps 2-3: do the stored UVs' boundary segments close into one simple polygon wound
    counter-clockwise?"""
    isl = disk.island
    # Every corner of a vertex where its first corner is: then the two sides of each interior
    # edge agree at both ends, and the UV boundary is the mesh's loop through the vertices' UVs.
    uv = corner_uv.reshape(-1, 2).take(disk.first, axis=0)
    if not np.logical_and.reduce(uv.take(isl.tris, axis=0) == corner_uv, axis=None):
        return False
    p = uv.take(isl.loops[0], axis=0)                     # segment i: p[i] -> p[i + 1]
    q = np.concatenate([p[1:], p[:1]])
    return _simple_or_not(p, q)


def simple_ccw_loop(p):
    """Is the polygon through the points p (n,2) float64, in order, simple and wound
    counter-clockwise (steps 3's test of a boundary loop's UVs)?"""
    q = np.concatenate([p[1:], p[:1]])
    return _simple_or_not(p, q)


def _simple_or_not(p, q):
    """Step 3 on the segments p[i] -> q[i] = p[i + 1]: the star-shaped test, else the full test
    (both exact: each answers as the other where it answers; ``turns_once``, a refusal of
    polygons the full test refuses too, is not asked first: most maps certified here are one
    to one, and most ring patches of the issue-21 disks are not star-shaped, so the full test
    runs on them anyway)."""
    return _star_shaped(p, q) or _simple_ccw(p, q)


def turns_once(z):
    """A necessary test, cheap (a few microseconds; the unfold asks it of every iterate that is
    the least yet): may the polygon through the points z (n,) complex, in order, be simple and
    wound counter-clockwise? False: it surely is not (its turning number, ``turning``, is not
    1)."""
    t = turning(z)
    return t is None or t == 1


def turning(z):
    """The turning number of the closed polygon through the points z (n,) complex, in order, or
    None where it cannot be told for sure.

    Its exterior angles (each in (-pi, pi], the argument of ``conj(e_i) e_(i+1)`` for
    consecutive segments e) add up to 2 pi times it: 1 for a simple polygon wound
    counter-clockwise, -1 clockwise (a hole's loop), 0, 2 or more for a boundary that curls
    over itself. The sum's rounding is far below pi: only an angle near +-pi (a segment folding
    back onto the last) may be read with the wrong sign, so where one is not clear of its
    rounding the answer is None."""
    e = np.concatenate([z[1:], z[:1]])
    e -= z
    t = np.concatenate([e[1:], e[:1]])
    t *= e.conj()
    a = np.arctan2(t.imag, t.real)
    s = float(a.sum())
    # a sign read wrong needs |Im t| within rounding of |t| (~1e-16): |a| within ~1e-15 of pi
    if not np.abs(a, out=a).max() < np.pi - 1e-12:      # (NaN too)
        return None
    return round(s / (2.0 * np.pi))


def _star_shaped(p, q):
    """A sufficient test, the common case: seen from the polygon's centroid (of its area: the
    mean of its points, weighted by where they lie along the boundary, missed it on two of the
    issue-21 disks), every segment turns counter-clockwise (``segments._orient``'s sign, clear of
    its rounding bound) and the turns add up to one full turn. The segments then cover the
    directions from that point once each, so only consecutive ones meet, at their shared end: a
    simple polygon, wound counter-clockwise. Any point would do: the centroid's rounding only
    decides whether the test answers."""
    w = p[:, 0] * q[:, 1] - p[:, 1] * q[:, 0]
    a3 = 3.0 * np.add.reduce(w)         # 6 times the signed area, over 2
    if not a3 > 0.0:
        return False
    c = np.array([(p[:, 0] + q[:, 0]) @ w, (p[:, 1] + q[:, 1]) @ w]) / a3
    d, e = p - c, q - c
    l, r = d[:, 0] * e[:, 1], d[:, 1] * e[:, 0]
    cross = l - r
    if not np.logical_and.reduce(cross > 1e-15 * (np.abs(l) + np.abs(r))):
        return False
    turns = np.add.reduce(np.arctan2(cross, d[:, 0] * e[:, 0] + d[:, 1] * e[:, 1]))
    return abs(turns - 2.0 * np.pi) < 1.0               # a whole number of turns, each in (0, pi)


def _simple_ccw(p, q):
    """The polygon p[i] -> q[i] = p[i + 1] tested as ``overlap.island_overlaps`` tests one
    loop: no point twice, no fold at a shared end, no other pair of segments meeting, positive
    area."""
    nb = len(p)
    c = np.sort(p[:, 0] + 1j * p[:, 1])
    if (c[1:] == c[:-1]).any():                           # a UV point passed twice: a pinch
        return False
    # consecutive segments (a, s), (s, c) fold back when collinear and c on a's side of s
    da, dc = p - q, np.concatenate([q[1:], q[:1]]) - q
    if ((da[:, 0] * dc[:, 1] - da[:, 1] * dc[:, 0] == 0)
            & (da[:, 0] * dc[:, 0] + da[:, 1] * dc[:, 1] > 0)).any():
        return False
    i, j = _box_pairs(p, q)
    gap = np.abs(i - j)
    other = (gap != 1) & (gap != nb - 1)                  # consecutive pairs share their end
    i, j = i[other], j[other]
    if len(i) and _meet(p, q, i, j):
        return False
    twice_area = np.bincount(np.zeros(nb, dtype=np.int64),
                             p[:, 0] * q[:, 1] - p[:, 1] * q[:, 0], 1)[0]
    return bool(twice_area > 0)


def _meet(p, q, i, j):
    """Does any segment i meet its segment j, segments with no end in common? The four
    orientation signs (``segments._orient``) when all are clear of their rounding bound, else
    ``segments.segments_meet``'s robust predicate."""
    # orientations of c and d against segment (a, b), of a and b against (c, d): (4, k) arrays
    # of their points (p's rows, then q's), the arithmetic of segments._orient
    k, nb = len(i), len(p)
    ends = np.concatenate([p, q])
    first = np.concatenate([i, i, j, j])
    s = ends.take(first, axis=0).reshape(4, k, 2)
    t = ends.take(first + nb, axis=0).reshape(4, k, 2)
    u = ends.take(np.concatenate([j, j + nb, i, i + nb]), axis=0).reshape(4, k, 2)
    l = (t[..., 0] - s[..., 0]) * (u[..., 1] - s[..., 1])
    r = (t[..., 1] - s[..., 1]) * (u[..., 0] - s[..., 0])
    o = l - r
    if not (np.abs(o) > 1e-15 * (np.abs(l) + np.abs(r))).all():
        return bool(segments_meet(p, q, i, j).any())
    sign = o > 0
    return bool(((sign[0] != sign[1]) & (sign[2] != sign[3])).any())


def _box_pairs(p, q):
    """Pairs (i, j) of segments whose bounding boxes meet (touching included), each pair once:
    a sweep over x (segments sorted by their least x, each paired with those that start before
    it ends), then the y intervals compared. (k,) int64 each."""
    lo, hi = np.minimum(p, q), np.maximum(p, q)
    nb = len(p)
    order = np.argsort(lo[:, 0], kind="stable")
    end = np.searchsorted(lo[order, 0], hi[order, 0], side="right")
    count = np.maximum(end - np.arange(nb) - 1, 0)
    a = np.repeat(np.arange(nb), count)
    b = a + 1 + np.arange(len(a)) - np.repeat(np.cumsum(count) - count, count)
    i, j = order[a], order[b]
    meet = (lo[i, 1] <= hi[j, 1]) & (lo[j, 1] <= hi[i, 1])
    return i[meet], j[meet]
