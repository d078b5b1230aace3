"""Conformal maps of many charts in one solve, and what each chart's map costs in distortion.

A chart passes when its free-boundary conformal map (LSCM) has no flipped face, conformal
distortion within C (Lipman 2012, eq. 4.9), stretch within S (the singular-value bounds of
section 6.3, measured after scaling the chart to its 3D area) and a boundary that does not cross
itself (so the flip-free map of the disk is injective).
"""
from dataclasses import dataclass

import numpy as np

from ..solvers.lscm import FaceGeometry, face_geometry, spd_solver  # noqa: F401
from ..solvers.lscm import _lscm_system   # lscm_pinned's assembly, to free memory before factoring
from ..solvers.threads import halves, map_blocks, map_queue
from .crossings import boundary_crossings
from .orders import BATCH_VERTICES, SLACK, ordered_solver
from ..trim import CHUNK, release_memory
from ..unwrapping.batched import _far_pairs
from ..array_calls import einsum, quiet

# Charts are accepted a little inside S: bending a map into C moves its stretch slightly.
MARGIN = 0.98
# Area-weighted mean conformal distortion a chart's conformal map may have (the result's mean
# is the area-weighted mean of its charts'): on coarse curved meshes a map within C and S can
# still average far above 1 (each vertex's angle defect is flattened into a few large faces:
# an 80-face icosphere in two charts averaged 1.23, a 16-sided cylinder 1.32). ``mean_cap``:
# 1 + MEAN_SLOPE for C <= 2, growing with a looser bound. 0.07 keeps the coarse test meshes'
# results at <= 1.065 with seams within xatlas's; 0.05 cost them more seam.
MEAN_SLOPE = 0.07
# Charts of one solve are split into two systems factored side by side (``solvers.threads``)
# when each holds at least this many vertices (below it, the split costs more than it saves).
PARALLEL_VERTICES = 1500
# ... but a batch of more vertices than this is solved in runs of charts holding at most
# RUN_VERTICES vertices together (a larger chart alone), two runs side by side: the LDL^T
# factors are the seam search's memory peaks (measured on a 500k-face mesh: ~310 MB at its
# largest, a 183k-vertex chart; a merge round's batch of unions in two halves: ~250k vertices,
# ~200 MB each). Two runs of 25k vertices at once hold about what one of 50k did; halves of a
# 100k-vertex batch side by side were the search's peak (a merge round, 477-494 MB).
SEQUENTIAL_VERTICES = 50_000
# Runs of 12.5k rather than 25k vertices: with the batches' own arrays gone (each run forms
# its own), two 25k-vertex factors side by side and their threads' freed heap were a merge
# round's peak on a 500k-face mesh (~360 MB, ~345 with one thread). A run's charts are
# eliminated in qdldl's AMD order of their block-diagonal system, each chart's block as
# alone (the same bits: dino subdivided twice and three times give the same maps).
RUN_VERTICES = 12_500


def mean_cap(C):
    """The largest area-weighted mean conformal distortion a chart's map may have at bound C:
    ``1 + MEAN_SLOPE * max(C - 1, 1)`` (1.07 at C = 2; a looser C relaxes it in proportion)."""
    return 1.0 + MEAN_SLOPE * max(float(C) - 1.0, 1.0)


@dataclass(frozen=True)
class ChartMaps:
    """Conformal maps of a list of charts (islands), stacked.

    Attributes
    ----------
    uv : (nv,) complex128, every chart's vertices in turn, each chart scaled to its 3D area
    voff, foff : (k+1,) int64, offsets of each chart's vertices and faces
    distortion : (f,) float64, conformal distortion per face (inf when flipped)
    stretch : (f,) float64, ``max(sigma_1, 1/sigma_2)`` per face (inf when flipped)
    max_distortion, max_stretch : (k,) float64 per chart
    mean_distortion : (k,) float64, area-weighted mean conformal distortion per chart (inf
        when a face is flipped)
    crossings : (k,) int64, pairs of boundary edges of the chart that cross in UV (-1: not
        counted, see ``chart_maps``' limits)
    sigma : (f,2) float64, singular values ``(|alpha|+|beta|, |alpha|-|beta|)`` per face (the
        second <= 0 when flipped), each chart scaled to its 3D area: any union of a chart's faces
        scaled to its own area has the stretch ``max(s sigma_1, 1/(s sigma_2))`` with one
        factor ``s`` (see ``piece_stretch``)
    u : (nv,) complex128, every chart's map as solved: unit-area normalisation, its two
        ``_far_pairs`` vertices at 0 and 1 (as ``unwrapping.batched.conformal_islands`` solves it)
    """
    uv: np.ndarray
    voff: np.ndarray
    foff: np.ndarray
    distortion: np.ndarray
    stretch: np.ndarray
    max_distortion: np.ndarray
    max_stretch: np.ndarray
    crossings: np.ndarray
    sigma: np.ndarray
    mean_distortion: np.ndarray
    u: np.ndarray

    def remember(self, charts, passed, known):
        """Put the maps of the charts that ``passed`` into ``known`` (sorted faces' bytes ->
        map), for the final unwrap to certify rather than solve again. Copies: a view would
        keep the whole batch's map alive (on a 500k-face mesh ~20 MB of maps held to the end
        for ~4 MB of charts that passed)."""
        for j in passed.ravel().nonzero()[0]:
            known[charts[j].faces.tobytes()] = self.u[self.voff[j]:self.voff[j + 1]].copy()


def chart_maps(V, charts, geom=None, limits=None, orders=None):
    """LSCM of every chart in one block-diagonal solve, with per-face distortion and stretch.

    Parameters
    ----------
    V : (n,3) float64
    charts : list of mesh.Island, each valid with exactly one boundary loop
    geom : FaceGeometry of the mesh the charts' faces index, optional (else computed here)
    limits : (stretch, mean) floats, optional: count boundary crossings only for the charts
        whose map is flip-free with max stretch and mean distortion within them (the others fail
        anyway); their ``crossings`` are -1
    orders : orders.Orders of the mesh, optional: the systems are eliminated in the order
        its keys give (given, reused or made here) rather than in qdldl's AMD order, in a
        batch of at most ``orders.BATCH_VERTICES`` vertices

    Returns
    -------
    ChartMaps
    """
    k = len(charts)
    nvs = np.array([len(c.vertices) for c in charts])
    nfs = np.array([len(c.faces) for c in charts])
    voff = np.concatenate([[0], nvs.cumsum()])
    foff = np.concatenate([[0], nfs.cumsum()])
    n = int(voff[-1])
    if n > BATCH_VERTICES:  # a large batch's factors are memory peaks: AMD's fill (orders.py)
        orders = None
    # The batch's mesh vertices (chart after chart), formed once: held through the solves only
    # where ``orders`` reads them (a batch of at most ``orders.BATCH_VERTICES`` vertices).
    gv = np.concatenate([c.vertices for c in charts])
    P = V.take(gv, axis=0)   # (rows: ``take``, ~4x cheaper than numpy's fancy index)
    idx = _far_pairs(P, charts, voff)
    del P                   # the batch's positions are not held through the factors
    if orders is None:
        gv = None
    val = np.tile(np.array([0.0, 1.0], np.complex128), k)

    vk, fresh = orders.keys(charts, voff, gv) if orders is not None else (None, None)
    budget = SLACK * orders.fill if orders is not None else 0.0

    def run(r):
        """The charts r[0]:r[1] alone: their system solved and their per-face numbers. Each
        run forms its own triangles and (without ``geom``) face geometry, so a batch's are
        never held whole beside the factors (on a 500k-face mesh ~100 bytes a face of the
        batch's, 30-35 MB of a round's 300k faces); every face's numbers are its own and every
        per-chart sum runs over the chart's faces in order, as over the whole batch: the same
        bits."""
        a, b = r
        cs = charts[a:b]
        tris = np.concatenate([c.tris + int(voff[j] - voff[a]) for j, c in zip(range(a, b), cs)])
        nv = int(voff[b] - voff[a])
        if geom is None:
            g = face_geometry(V[np.concatenate([c.vertices for c in cs])], tris)
            faces = np.arange(len(tris))
        else:
            g, faces = geom, np.concatenate([c.faces for c in cs])
        args = (g, faces, tris, nv, idx[2 * a:2 * b] - voff[a], val[2 * a:2 * b])
        if vk is None:
            u, info = _lscm_pinned(*args), None
        else:
            u, info = _lscm_ordered(*args, vk[voff[a]:voff[b]], budget)
        return (info, u) + _per_face(u, g, faces, tris, nfs[a:b], nvs[a:b])
    j = halves(nvs, PARALLEL_VERTICES)
    if n > SEQUENTIAL_VERTICES:     # two factors of at most RUN_VERTICES vertices at a time,
        #                             a larger chart's alone (two such factors side by side
        #                             were the seam search's peak on a 500k-face mesh)
        runs = _runs(nvs, RUN_VERTICES)
        out = map_queue(run, runs, [voff[b] - voff[a] > RUN_VERTICES for a, b in runs])
    elif j is None:
        runs, out = [(0, k)], [run((0, k))]
    else:                   # two runs of charts, one system each, side by side
        runs = [(0, j), (j, k)]
        out = map_blocks(run, runs)
    if orders is not None:
        orders.solved(charts, runs, [(fill, rank, gv[voff[a]:voff[b]][free])
                                     for (a, b), ((fill, rank, free), *_) in zip(runs, out)],
                      fresh)
    u_solved, uv, D, St, a, b, meanD = (np.concatenate([x[i] for x in out])
                                        for i in range(1, 8))
    out = None
    maxD = np.maximum.reduceat(D, foff[:-1])
    maxS = np.maximum.reduceat(St, foff[:-1])
    if limits is None:
        cross = boundary_crossings(uv, [c.loops[0] + voff[j] for j, c in enumerate(charts)])
    else:
        ask = (np.isfinite(maxD) & (maxS <= limits[0]) & (meanD <= limits[1])).ravel().nonzero()[0]
        cross = np.full(k, -1, dtype=np.int64)
        cross[ask] = boundary_crossings(uv, [charts[j].loops[0] + voff[j] for j in ask])
    return ChartMaps(uv, voff, foff, D, St, maxD, maxS, cross, np.stack([a + b, a - b], axis=1),
                     meanD, u_solved)


def _per_face(u, geom, faces, tris, nfs, nvs):
    """A run's per-face numbers from its map ``u`` (its charts' vertices in turn, ``nfs`` and
    ``nvs`` faces and vertices each; ``faces`` index ``geom``): (uv, distortion, stretch,
    |alpha|, |beta|, each chart's mean distortion), ``CHUNK`` faces at a time (each face's
    are its own: the same bits; the (f,3) complex coefficients, their conjugates and the
    corners' UVs at once were ~250 bytes per face)."""
    k = len(nfs)
    face_c = np.repeat(np.arange(k), nfs)
    vert_c = np.repeat(np.arange(k), nvs)
    nf = len(tris)
    w = np.empty(nf)
    for i in range(0, nf, CHUNK):
        t = tris[i:i + CHUNK]
        e1 = u[t[:, 1]] - u[t[:, 0]]
        e2 = u[t[:, 2]] - u[t[:, 0]]
        w[i:i + CHUNK] = 0.5 * (e1.conj() * e2).imag
    t = e1 = e2 = None
    # Scale each chart so its UV area equals its (unit-normalised) 3D area: sigma are then the
    # singular values of the map with the chart at its 3D size.
    uv_area = np.bincount(face_c, w, minlength=k)
    del w
    with quiet("invalid", "divide"):
        s = np.sqrt(1.0 / np.abs(uv_area))
    s[~np.isfinite(s)] = 1.0
    us = u * s[vert_c]
    A3 = geom.area[faces]
    area = np.bincount(face_c, A3, minlength=k)
    root = np.sqrt(area)
    a, b = np.empty(nf), np.empty(nf)
    for i in range(0, nf, CHUNK):
        f = slice(i, i + CHUNK)
        cb = geom.cb.take(faces[f], axis=0) * root[face_c[f]][:, None]
        ut = us[tris[f]]
        a[f] = np.abs(einsum("fk,fk->f", cb.conj(), ut))
        b[f] = np.abs(einsum("fk,fk->f", cb, ut))
    cb = ut = None
    with quiet("invalid", "divide"):
        ok = a > b
        D = np.where(ok, (a + b) / (a - b), np.inf)
        St = np.where(ok, np.maximum(a + b, 1.0 / (a - b)), np.inf)
    D[~np.isfinite(D)] = np.inf
    St[~np.isfinite(St)] = np.inf
    with quiet("invalid"):
        meanD = np.bincount(face_c, A3 * D, minlength=k) / area
    meanD[~np.isfinite(meanD)] = np.inf
    return us * np.sqrt(area)[vert_c], D, St, a, b, meanD


def _lscm_pinned(geom, faces, tris, n, idx, val):
    """``solvers.lscm.lscm_pinned`` on the terms of ``faces`` (``geom``: FaceGeometry), formed
    here and dropped with the assembly's temporaries before the factorisation, whose memory is
    handed back to the operating system first (``trim.release_memory``: large charts only)."""
    return _lscm_ordered(geom, faces, tris, n, idx, val)[0]


def _lscm_ordered(geom, faces, tris, n, idx, val, keys=None, budget=0.0):
    """``_lscm_pinned``, with ``keys`` (n,) the unknowns eliminated in their vertices' order
    (``orders.ordered_solver``, ``budget`` its fill limit). Returns (u, (the fill and ranks
    ``ordered_solver`` returns, the free vertices) or None without keys)."""
    A, rhs, u, free = _lscm_system(geom.cbw(faces), geom.cb.take(faces, axis=0), tris, n, idx, val,
                                   triplets=keys is not None)
    release_memory(len(tris))
    info = None
    if keys is None:
        solve = spd_solver(A, upper=True)
    else:
        solve, fill, rank = ordered_solver(A, keys[free], budget)
        info = (fill, rank, free)
    x = solve(rhs)
    nf = len(free)
    u[free] = x[:nf] + 1j * x[nf:]
    return u, info


def _runs(sizes, limit):
    """Consecutive runs ``(a, b)`` of charts of ``sizes`` vertices, each as many as fit within
    ``limit`` together (at least one)."""
    runs, a, total = [], 0, 0
    for j, s in enumerate(sizes.tolist()):
        if j > a and total + s > limit:
            runs.append((a, j))
            a, total = j, 0
        total += s
    runs.append((a, len(sizes)))
    return runs


def piece_stretch(sigma, area3, label, k):
    """Stretch of the conformal map of a chart restricted to pieces of it, each piece scaled
    to its own 3D area (no new solve: the restriction of a conformal map is one of the piece).

    Parameters
    ----------
    sigma : (f,2) float64, the chart's singular values per face (``ChartMaps.sigma``)
    area3 : (f,) float64, 3D face areas
    label : (f,) int64, piece of each face in 0..k-1
    k : int

    Returns
    -------
    (k,) float64, ``max(s sigma_1, 1/(s sigma_2))`` over each piece's faces with
    ``s = sqrt(sum area3 / sum area3 sigma_1 sigma_2)`` (inf where a face is flipped)
    """
    uv_area = np.bincount(label, area3 * sigma[:, 0] * sigma[:, 1], minlength=k)
    with quiet("invalid", "divide"):
        s = np.sqrt(np.bincount(label, area3, minlength=k) / uv_area)[label]
        st = np.where(sigma[:, 1] > 0, np.maximum(s * sigma[:, 0], 1.0 / (s * sigma[:, 1])),
                      np.inf)
    st[~np.isfinite(st)] = np.inf
    out = np.full(k, -np.inf)
    np.maximum.at(out, label, st)
    return out
