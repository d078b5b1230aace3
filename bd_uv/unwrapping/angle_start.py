"""An angle-based start for a disk whose conformal map is bad (issue 21 item 1: auto on disks
whose conformal start flips or lies over itself).

The free-boundary conformal map (LSCM, two far vertices pinned) can flip faces or lie over
itself on disks with long curved parts and saw-toothed boundaries: on camel's 1,324-face patch,
homer's 3,521-face patch and libigl elephant's 2,004-face patch its max distortion is inf (a
flipped face), inf and 19.3 (Blender's LSCM: 6.6, 56, 104), and the bound search from it ends in
a map that lies over itself at C 2.8-3.2, which the overlap repair cuts into 14-19 pieces.
Blender's ABF lays the same disks out at 1.28, 1.63 and 1.20.

Here the faces' angles are solved first, as Linear ABF does (Zayer, Levy and Seidel 2007): the
least change ``e`` of the 3D angles (weighted by ``1 / beta^2``, ABF's weights; the angles at an
interior vertex first scaled to add up to 2 pi) such that, to first order, every triangle's
angles add up to pi, every interior vertex's to 2 pi, and the law of sines closes round every
interior vertex (the wheel condition). One sparse symmetric solve of the constraints'
normal equations ``(A W^-1 A^T) lam = r``, ``e = W^-1 A^T lam``. To that, at every boundary vertex
whose angles add up to CAP x 2 pi or more (a saddle at the boundary, or a tooth of it, round which
any map close to conformal wraps), their sum is asked to be CAP x 2 pi: the UV boundary then
turns less than a full turn there. Each face is rebuilt from its angles at its own area
(``capped.from_angles``) and the conformal map of these shapes is solved (``one_disk.conformal``:
the same system, pins and elimination order as the conformal map). Where the map still wraps
round a boundary vertex (the solve is first order), that vertex's sum is asked lower, by the
share it missed, up to ATTEMPTS solves.

On the five disks above and two more (bunny's 1,595-face and ChineseDragon's 1,577-face
patches) its max distortion is 1.21-1.53 where Blender ABF's is 1.20-1.63 (3.76 against 4.13 on
ChineseDragon), flip-free, in one solve of the angles and one conformal solve (7-22 ms).
"""
import numpy as np

from ..geometry import corner_angles, gradient_operators
from ..solvers import ordered_ldl
from ..solvers.face_operators import as_csc, csc_arrays
from ..solvers.lscm import face_geometry_of, spd_solver
from .capped import from_angles
from .disk_conformal import _qdldl_solve, conformal
from .disk_certificate import measure_disk, turning

__all__ = ["angle_start", "bent_first", "better_start", "linear_abf", "max_distortion"]

CAP = 0.97          # a boundary vertex whose angles reach CAP x 2 pi is held at CAP x 2 pi
ATTEMPTS = 4        # conformal solves at most (the angles scaled further where the map still wraps)
LEAST_ANGLE = 1e-3  # the solved angles kept above this (a first-order step may overshoot)
NEAR = 6            # sides of a boundary at most this far apart are checked for a crossing
# A conformal start whose max distortion is over this is bad (``target_watch.EFFORT_START``'s
# value: the bound search's budget does not apply from there either)
BAD = 2.0
# Up to this many faces a bad conformal start is replaced (``better_start``; above, the angle
# start is made only before a cut, ``island_solve.angle_unfolder``): on lion-head.off (16.7k
# faces, conformal max 2.67, angle start 2.93: not taken) and mannequin-devil.off (25.9k, its
# conformal map and its angle start flip) the angle start cost 120 and 220 ms of CPU for
# nothing (auto 0.32 -> 0.45 s, 0.49 -> 0.71 s; C = 5 0.23 -> 0.41 s)
ANGLE_FACES = 5000
# Over this many faces ``bound="auto"`` asks ``better_start`` before ``disk_auto``'s search from
# the conformal start, which a better angle start replaces: igl bunny's 1,595-face patch
# (conformal max 2.49, angle start 1.29) searched from its conformal start first (99
# iterations, 16 ms of CPU) for a map lying over itself, then from its angle start (auto 52 ->
# 36 ms, the same C). Up to it (``bound_search.ONE_PRODUCT_FACES``' 1,000) the search from the
# conformal start is kept: on 150-162-face disks of cow.off and three bumps its map certifies
# and is the one the unfold and the mean's relaxation are measured against
FIRST_FACES = 1000
# A flip-free angle start whose boundary turns once is searched from up to this max distortion,
# whatever ``bound_limit`` says: the search's map, not the start, must be within that limit
# (``strategies.minimise`` with ``one_to_one``), and the alternative is a cut. Under
# ``bound_limit`` (1,000) as the gate, disks whose conformal start lay over itself with angle
# starts of 1,312-5,265 were cut into 5-24 pieces; searched from, each was one island at the
# same or a lower C in 58-82 % of the CPU (issue21-unseen16-2026-11-28.md, section 3). No
# angle start over 1e4 turned up in a scan of 600 patches.
ANGLE_LIMIT = 1e5
# At a number C up to BENT_UP_TO, a conformal start flipping at least FLIPS_BENT faces, or
# flipping and turning once, is bent into C (the general path) without its angle start made
# first (``bent_first``): on 21 disks whose conformal start flips
# (benchmarks/results/issue21-c5x25-2026-11-28.md), every angle start taken at C = 5 came from
# a start flipping one face and turning more than once (max 1.28-1.86); those of starts
# flipping two or more faces (2-60: three_peaks.off 30) or turning once had max 5.3 or more:
# made and left unused (three_peaks.off: ~18 ms of ~90 of CPU), or used only by the unfold of
# a bent map lying over itself, which now makes it there (``island_solve.unfolder``). Above
# BENT_UP_TO such an angle start may fit (5.3-7.5 on those disks) and is then the faster map
# (three_peaks.off at C = 8: 41 ms against 111 bent), so it is made first as before.
FLIPS_BENT = 2
BENT_UP_TO = 5.0


def linear_abf(disk, caps, beta=None):
    """Each face's corner angles (m,3), Linear ABF's solve of the disk's angles (see the
    module's docstring) with the angle sums ``caps`` (nv,) float64 (NaN: free) asked at
    boundary vertices; each row adds up to pi. None where the solve fails. ``beta``: the
    disk's 3D corner angles ``abs(corner_angles(disk.Z))`` where the caller has them."""
    isl = disk.island
    tris, nv = isl.tris, len(isl.vertices)
    m = len(tris)
    if beta is None:
        beta = np.abs(corner_angles(disk.Z))
    onb = np.zeros(nv, dtype=bool)
    onb[isl.loops[0]] = True
    flat = tris.ravel()
    vsum = np.bincount(flat, beta.ravel(), nv)
    inner = ~onb
    beta = beta * np.where(inner, 2.0 * np.pi / vsum, 1.0).take(tris)
    wi = (beta * beta).ravel()                  # W^-1: ABF's weights are 1 / beta^2
    iv = inner.nonzero()[0]
    vid = np.full(nv, -1, dtype=np.int64)
    vid[iv] = np.arange(len(iv))
    held = (onb & np.isfinite(caps)).nonzero()[0]
    hid = np.full(nv, -1, dtype=np.int64)
    hid[held] = np.arange(len(held))
    ni, nh = len(iv), len(held)
    # the triangles' rows are eliminated at once (their block of A W^-1 A^T is diagonal: each
    # holds its own three corners): the system left is the vertices' and wheels' rows R,
    # (R B R^T) lam_R = r_R - R W^-1 T^T D^-1 r_T, B = W^-1 - W^-1 T^T D^-1 T W^-1 block diagonal
    # (each triangle's 3 x 3 block: diag(w) - w w^T / sum(w)). Each triangle touches at most six
    # rows of R: the angle sums at its three corners' vertices (interior, or held at the
    # boundary) and the wheels round its interior vertices; R B R^T is assembled from those
    # 6 x 6 blocks at once (one sparse conversion; homer's 1,982-face strip: 5.3 -> 4.8 ms)
    cot = 1.0 / np.tan(beta)
    logsin = np.log(np.sin(beta))
    wheel = np.zeros(nv)
    rid = np.empty((m, 6), dtype=np.int64)      # each triangle's rows of R (-1: none)
    Rl = np.zeros((m, 6, 3))                    # ... and their entries at its three corners
    for k in range(3):
        k1, k2 = (k + 1) % 3, (k + 2) % 3
        v = tris[:, k]
        rid[:, k] = np.where(inner.take(v), vid.take(v),
                             np.where(hid.take(v) >= 0, 2 * ni + hid.take(v), -1))
        Rl[:, k, k] = 1.0
        rid[:, 3 + k] = np.where(inner.take(v), ni + vid.take(v), -1)
        Rl[:, 3 + k, k2] = cot[:, k2]
        Rl[:, 3 + k, k1] = -cot[:, k1]
        np.add.at(wheel, v, logsin[:, k2] - logsin[:, k1])
    none = rid < 0
    Rl[none] = 0.0
    w3 = wi.reshape(m, 3)
    dinv = 1.0 / w3.sum(axis=1)
    Rw = Rl @ w3[:, :, None]                    # (m, 6, 1): R W^-1 T^T per triangle
    RB = Rl * w3[:, None, :] - (Rw * dinv[:, None, None]) * w3[:, None, :]
    Ml = (RB @ Rl.transpose(0, 2, 1)).reshape(m, 36)       # (m, 6, 6), row by row
    # each pair of a triangle's rows once (its six rows are distinct), the entry of the upper
    # triangle of R B R^T: the pairs kept where both rows are (21 entries a triangle selected
    # instead of 36 tested: ~0.1 of linear_abf's ~3 ms on 1.1-1.3k faces; the same triplets,
    # those of one place in the same order: the same sums)
    ri, ci = rid.take(_PAIR_I, axis=1), rid.take(_PAIR_J, axis=1)
    low = ri > ci
    vals = np.where(low, Ml.take(_PAIR_J * 6 + _PAIR_I, axis=1), Ml.take(_PAIR_I * 6 + _PAIR_J,
                                                                         axis=1))
    ri, ci = np.where(low, ci, ri), np.where(low, ri, ci)
    keep = ri >= 0
    n = 2 * ni + nh
    bsum = np.bincount(flat, beta.ravel(), nv)
    r_t = np.pi - beta.sum(axis=1)
    at = (~none).ravel()
    shift = np.bincount(rid.ravel()[at], (Rw[:, :, 0] * (dinv * r_t)[:, None]).ravel()[at], n)
    rhs = (np.concatenate([2.0 * np.pi - bsum.take(iv), -wheel.take(iv),
                           caps.take(held) - bsum.take(held)]) - shift)
    lam_r = _solved(disk.ranks, ri[keep], ci[keep], vals[keep], n,
                    np.concatenate([iv, iv, held]), ni, rhs)
    if lam_r is None:
        return None
    # (no row at all: a strip with no interior vertex, no boundary vertex held)
    lam = np.where(none, 0.0, lam_r.take(np.maximum(rid, 0))) if n else np.zeros((m, 6))
    RTlam = np.einsum("trc,tr->tc", Rl, lam)    # R^T lam_R at each corner
    lam_t = dinv * (r_t - np.einsum("tc,tc->t", w3, RTlam))
    angles = (beta + w3 * (RTlam + lam_t[:, None]))
    if not np.isfinite(angles).all():
        return None
    angles = np.maximum(angles, LEAST_ANGLE)
    return angles * (np.pi / angles.sum(axis=1))[:, None]


_PAIR_I, _PAIR_J = np.triu_indices(6)      # the pairs (i <= j) of a triangle's six rows


def _solved(ranks, rows, cols, vals, n, vertex, ni, rhs):
    """``linear_abf``'s system (n, n), its upper triangle's triplets (rows, cols, vals; a place
    may repeat: summed), solved for ``rhs``: each row is a vertex's (``vertex`` (n,): the
    interior vertices' angle sums, their wheels from row ``ni``, then the held boundary
    vertices'), eliminated in the vertices' order ``ranks`` (a vertex's sum, then its wheel) where
    the disk has one (``Disk.ranks``: the graph of these rows is its vertices' with two rows a
    vertex, as the conformal map's system, whose order serves here too; no AMD of the rows, no
    scipy matrix: camel's 1,324-face patch 3.3 -> 1.3 ms of CPU, the answer to 4e-15), else in
    qdldl's AMD order. None where the solve fails."""
    if n and ranks is not None and ordered_ldl.available():
        second = np.zeros(n, dtype=np.int64)
        second[ni:2 * ni] = 1
        f = ordered_ldl.Factor(rows, cols, vals, n, np.argsort(2 * ranks.take(vertex) + second,
                                                               kind="stable"), repeats=True)
        if f.lnz >= 0 and f.factor():
            return f.solve(rhs)
    # scipy's conversion's arrays, the repeated places summed (``face_operators.csc_arrays``),
    # read by qdldl without the scipy matrix (homer's 3,521-face patch: ~0.25 ms less); a
    # scipy matrix only where qdldl refuses them (``lscm.spd_solver``'s SuperLU)
    M = csc_arrays(vals, rows, cols, n, n)
    solve = _qdldl_solve(M)
    try:
        return (solve or spd_solver(as_csc(M), upper=True))(rhs)
    except (ValueError, RuntimeError, np.linalg.LinAlgError):
        return None


def angle_start(V, disk):
    """The conformal map (nv,) complex128 of the disk's faces rebuilt from Linear ABF's angles
    (``linear_abf``), its boundary held below a full turn round every boundary vertex; None
    where no solve of ATTEMPTS gives a flip-free map whose boundary turns once."""
    isl = disk.island
    tris, loop, nv = isl.tris, isl.loops[0], len(isl.vertices)
    flat = tris.ravel()
    full = 2.0 * np.pi
    beta = np.abs(corner_angles(disk.Z))     # the 3D angles, once for the caps and the solve
    theta3 = np.bincount(flat, beta.ravel(), nv)
    caps = np.full(nv, np.nan)
    caps[loop] = np.where(theta3.take(loop) >= CAP * full, CAP * full, np.nan)
    angles = linear_abf(disk, caps, beta)
    if angles is None:
        return None
    scale = np.ones(nv)
    shapes = None
    for _ in range(ATTEMPTS):
        shapes = _rebuilt(angles, scale, tris, disk.area, shapes)
        # (in qdldl's own order, over ``ordered_ldl.RANKED_VERTICES``, the disk's conformal
        # factorisation is refilled: ``Disk.factors``; homer's 3,521-face patch: ~7 ms a
        # solve anew, most of it the order)
        u = conformal(V, disk, shapes[1], shapes[2], disk.ranks, shapes[3], shapes[4])
        a = corner_angles(u.take(tris))
        if not (np.isfinite(u).all() and (a > 0.0).all()):
            return None
        theta = np.bincount(flat, a.ravel(), nv).take(loop)
        over = theta >= full
        if not over.any():
            if turning(u.take(loop)) != 1:
                return None                     # lies over itself elsewhere than round a vertex
            # a tooth of the boundary folded onto its neighbours: its reflex vertices held lower
            over = _near_crossings(u.take(loop)) & (theta > np.pi)
            if not over.any():
                return u
        # the angles there scaled down by the share the map missed (its sum over CAP x 2 pi),
        # the solve of the angles not made again (a conformal solve each)
        v = loop[over]
        scale[v] *= np.minimum(CAP * full / theta[over], CAP)
    return None


def _rebuilt(angles, scale, tris, area, last=None):
    """The faces rebuilt from the corner angles (m,3) scaled by ``scale`` (nv,) (``_scaled``,
    ``capped.from_angles`` at their areas): (the scales at their corners (m,3), their local
    corners Z, gradient operators G, ``lscm.FaceGeometry`` and the faces rebuilt since
    ``last``, None for all). Given the last attempt's (``last``, whose arrays are
    overwritten), only the faces where a corner's scale changed are rebuilt: each face's
    numbers are its own row's arithmetic, so the same bits as all faces rebuilt (homer's
    3,521-face patch: 5 and 13 of its faces in its 2nd-4th solves, ~0.5 ms of each saved; and
    its system patched there, ``disk_conformal.conformal(rebuilt=...)``)."""
    s = scale.take(tris)
    if last is None:
        Z = from_angles(_scaled(angles, scale, tris), area)
        G = gradient_operators(Z)
        return s, Z, G, face_geometry_of(Z, G, area), None
    _, Z, G, geom, _ = last
    faces = (s != last[0]).any(axis=1).nonzero()[0]
    if len(faces):
        t, a = tris.take(faces, axis=0), area.take(faces)
        Zf = from_angles(_scaled(angles.take(faces, axis=0), scale, t), a)
        Gf = gradient_operators(Zf)
        gf = face_geometry_of(Zf, Gf, a)
        Z[faces], G[faces], geom.cb[faces], geom.zarea[faces] = Zf, Gf, gf.cb, gf.zarea
    return s, Z, G, geom, faces


def _scaled(angles, scale, tris):
    """The corner angles (m,3) with those at each vertex scaled by ``scale`` (nv,) (where
    below 1), the rest of each face's pi given to its other corners pro rata (``capped``'s
    rule: a face whose corners are all scaled is scaled back to pi)."""
    s = scale.take(tris)
    faces = (s < 1.0).any(axis=1).nonzero()[0]
    if not len(faces):
        return angles
    s = s[faces]
    A = angles[faces] * s
    rest = np.where(s < 1.0, 0.0, A)
    share = rest.sum(axis=1)
    A += rest * ((np.pi - A.sum(axis=1)) / np.where(share > 0, share, 1.0))[:, None]
    none = share <= 0
    A[none] *= (np.pi / A[none].sum(axis=1))[:, None]
    out = angles.copy()
    out[faces] = A
    return out


def better_start(V, disk, u, C=None):
    """The angle start (``angle_start``) of a disk whose conformal map u (nv,) complex is bad:
    it flips a face, its boundary does not turn once (it lies over itself), or its max
    distortion is over BAD (over C, for a number C asked).

    For ``bound="auto"`` (C None) it is taken where its max distortion is below u's, or where
    u lies over itself without a flip and it is within ANGLE_LIMIT (the search from it must
    end within ``bound_limit``: ``strategies.minimise``); where u flips, only within BAD.
    three_peaks.off and mannequin-devil's 706-face patch, whose conformal maps flip, have
    angle starts at 6.3 and 5.6: from them auto ended at 2.122 and 3.536 against 2.075 and
    3.477 from the bent conformal map. Patches of cow.off whose conformal maps lie over
    themselves have angle starts up to 441 that the search unfolds to one island at 2.07-2.47
    (Linear ABF's first-order angles at the horns' tips), and two at 1,720 and 3,670, over
    ``bound_limit``, that the search from them unfolds too (conic steps from them did not, in
    3-4x the time). For a number C it is taken within C
    (``one_disk.fitted`` certifies it there).

    Not asked above ANGLE_FACES faces (None, None, False).

    Returns (the angle start taken or None (u is kept), the angle start found or None, whether
    u was found bad): every other disk keeps its conformal start."""
    if len(disk.island.tris) > ANGLE_FACES:
        return None, None, False
    loop = disk.island.loops[0]
    D0 = max_distortion(disk, u)
    over = turning(u.take(loop)) != 1
    if np.isfinite(D0) and D0 <= (BAD if C is None else C) and not over:
        return None, None, False
    v = angle_start(V, disk)
    if v is None:
        return None, None, True
    D = max_distortion(disk, v)
    if C is not None:
        ok = D <= C
    elif not np.isfinite(D0):           # the conformal map flips: bent, it may do better
        ok = D <= BAD
    else:
        ok = D < D0 or (over and D <= ANGLE_LIMIT)
    return (v if ok else None), v, True


def bent_first(disk, u, C):
    """Whether, at a number C (up to BENT_UP_TO), the disk's conformal map u (nv,) complex is
    bent into C without its angle start made first: it flips FLIPS_BENT faces or more, or
    flips and its boundary turns once. Its angle start is made only where the unfold of a bent
    map lying over itself asks for it."""
    if not C <= BENT_UP_TO:
        return False
    uc = u.take(disk.island.tris)
    corner_uv = np.empty(uc.shape + (2,))
    corner_uv[..., 0], corner_uv[..., 1] = uc.real, uc.imag
    flips = int(np.count_nonzero(~np.isfinite(measure_disk(corner_uv, disk.G)[0])))
    return flips >= FLIPS_BENT or (flips > 0 and turning(u.take(disk.island.loops[0])) == 1)


def _near_crossings(z):
    """(b,) bool, the vertices of the closed polygon z (b,) complex that lie between two of its
    sides at most NEAR sides apart that cross (a tooth of a UV boundary folded over). Every
    pair of sides k = 2..NEAR apart is tested at once (a (NEAR - 1, b) array: 0.32 -> 0.09 ms
    on a 400-side loop against a roll a pair and a roll a marked vertex); the few that cross
    mark their vertices one by one."""
    b = len(z)
    marked = np.zeros(b, dtype=bool)
    ks = np.arange(2, min(NEAR, b - 2) + 1)
    if not len(ks):
        return marked
    i = np.arange(b)
    j = i + ks[:, None]                     # side i runs from vertex i to i + 1
    j %= b
    p, q = z, z.take((i + 1) % b)
    p2, q2 = z.take(j), z.take((j + 1) % b)

    def side(a, c, d):
        w = (c - a).conj() * (d - a)
        return w.imag
    cross = ((side(p, q, p2) * side(p, q, q2) < 0.0)
             & (side(p2, q2, p) * side(p2, q2, q) < 0.0))
    for row, s in zip(*cross.nonzero()):    # the vertices i + 1 .. i + k
        marked[(s + 1 + np.arange(ks[row])) % b] = True
    return marked


def max_distortion(disk, u):
    """Max conformal distortion (inf where a face flips) of the map u (nv,) complex."""
    uc = u.take(disk.island.tris)
    corner_uv = np.empty(uc.shape + (2,))
    corner_uv[..., 0], corner_uv[..., 1] = uc.real, uc.imag
    return float(measure_disk(corner_uv, disk.G)[0].max())
