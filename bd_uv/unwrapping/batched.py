"""Many islands at once: one conformal solve and one certification for every island that fits.

A hard-surface asset has hundreds to thousands of small islands, and per-island Python work (a
problem object, its operators, a factorisation) costs milliseconds each. Islands without pins whose
free-boundary conformal map (LSCM) already fits the bound need nothing else, so they are solved
together: one block-diagonal LSCM system with each island's two far boundary vertices fixed, one
sparse factorisation, distortion and certification vectorised over all faces. Islands that do not
fit go on to the per-island strategies with their conformal map as start.
"""
import time

import numpy as np

from ..geometry import face_areas
from ..solvers.lscm import face_geometry, lscm_pinned
from ..solvers.ordered_ldl import FIXED_RANKED, vertex_ranks
from .margins import STORE_HEADROOM
from .results import IslandResult
from ..trim import CHUNK


def conformal_islands(V, islands, C, known=None):
    """Conformal maps of many islands in one solve, and the results of those that fit C.

    Parameters
    ----------
    V : (n,3) float64
    islands : list of mesh.Island, valid (no error), without pins
    C : float, the bound; None: no island is certified here, every map is returned as a start
        (``bound="auto"``: each island's search starts from it)
    known : dict island index -> (nv,) complex128, optional, conformal maps already solved the
        same way (unit-area normalisation, ``_far_pairs`` pinned at 0 and 1): not solved again.
        They are certified like the others, from the final UVs.

    Returns
    -------
    done : dict island index -> IslandResult (certified, flag "initial_map")
    starts : dict island index -> (nv,) complex128, the conformal map (unit-area normalisation) of
        each island that did not fit, for the per-island path
    """
    t0 = time.perf_counter()
    if not islands:
        return {}, {}
    nvs = np.array([len(i.vertices) for i in islands])
    nfs = np.array([len(i.faces) for i in islands])
    voff = np.concatenate([[0], np.cumsum(nvs)])
    foff = np.concatenate([[0], np.cumsum(nfs)])
    k = len(islands)
    face_isl = np.repeat(np.arange(k), nfs)
    vert_isl = np.repeat(np.arange(k), nvs)
    verts = np.concatenate([i.vertices for i in islands])
    tris = np.concatenate([i.tris for i in islands]) + voff[face_isl][:, None]
    P = V[verts]
    known = {} if known is None else known
    have = np.array([i.index in known for i in islands], dtype=bool)
    if have.all() and C is None:    # nothing to solve or certify
        return {}, {i.index: np.asarray(known[i.index], dtype=np.complex128) / 1.0
                    for i in islands}
    # alpha = sum ca u, beta = sum cb u per face (eq. 4.19); each island normalised to unit area
    # (as IslandProblem does): the coefficients grow by sqrt(area), the LSCM terms do not change.
    # With every map known and more than CHUNK faces, the coefficients are formed CHUNK faces
    # at a time where they are read (twice), not held for all faces (~64 bytes a face: 32 MB
    # of a 500k-face mesh's final unwrap, the seam search's peak there).
    held = not have.all() or len(tris) <= CHUNK
    geom = face_geometry(P, tris) if held else None
    A3 = geom.area if held else np.empty(len(tris))
    if have.all():
        u = np.concatenate([np.asarray(known[i.index], dtype=np.complex128) for i in islands])
    else:
        # The islands not known are solved together (one block system on their vertices).
        idx = _far_pairs(P, islands, voff)
        val = np.tile(np.array([0.0, 1.0], dtype=np.complex128), k)
        if have.any():          # known islands' vertices are all fixed at their known map
            kv = np.flatnonzero(have[vert_isl])
            kidx = np.concatenate([known[i.index] for i, h in zip(islands, have) if h])
            own = ~have[np.repeat(np.arange(k), 2)]
            idx = np.concatenate([idx[own], kv])
            val = np.concatenate([val[own], kidx])
        # in the vertices' order (up to RANKED_VERTICES; qdldl's own above), which a bound
        # search's factor reuses ("auto", or a C whose map lies over itself); at a fixed C from
        # FIXED_RANKED vertices (three_peaks:554, unfolded: C = 5 / ABF 0.94-1.01 -> 0.84-0.91)
        u = lscm_pinned(geom.cbw(), geom.cb, tris, len(verts), idx, val,
                        ranks=vertex_ranks(tris, len(verts))
                        if C is None or len(verts) >= FIXED_RANKED else None)
    if C is None:
        return {}, {isl.index: u[voff[j]:voff[j + 1]] / 1.0 for j, isl in enumerate(islands)}
    if held:                    # the positions are read again only to form coefficients
        P = None
    m = len(tris)

    def cb(f):                  # beta's coefficients of the faces f (a slice)
        return geom.cb[f] if held else face_geometry(P, tris[f]).cb
    if not held:                # the areas first: the islands' totals scale every face
        for i in range(0, m, CHUNK):
            A3[i:i + CHUNK] = face_areas(P, tris[i:i + CHUNK])
    area = np.bincount(face_isl, A3, minlength=k)
    root = np.sqrt(area)[face_isl]
    # Per-face numbers CHUNK faces at a time (the same bits; the whole of a 500k-face mesh's
    # corner maps and coefficients at once were the seam search's last memory peak).
    a, b, sa = np.empty(m), np.empty(m), np.empty(m)
    for i in range(0, m, CHUNK):
        f = slice(i, i + CHUNK)
        uc = u[tris[f]]
        cf = cb(f)
        a[f] = np.abs(np.einsum("fk,fk->f", cf.conj(), uc)) * root[f]
        b[f] = np.abs(np.einsum("fk,fk->f", cf, uc)) * root[f]
        e1 = uc[:, 1] - uc[:, 0]
        e2 = uc[:, 2] - uc[:, 0]
        sa[f] = 0.5 * (e1.conj() * e2).imag
    with np.errstate(invalid="ignore", divide="ignore"):
        D = np.where(a > b, (a + b) / (a - b), np.inf)
    maxD = np.maximum.reduceat(D, foff[:-1])
    fit = maxD * (1.0 + STORE_HEADROOM) <= C
    del a, b, D, root                       # dead before the certification's per-face arrays

    # Fitting islands: UV area = 3D area, bounding box at (0, 0), as IslandProblem's finish.
    uv_area = np.bincount(face_isl, sa, minlength=k)
    del sa
    with np.errstate(invalid="ignore", divide="ignore"):
        s = np.sqrt(area / uv_area)
    us = u * s[vert_isl]
    lo = (np.minimum.reduceat(us.real, voff[:-1]) + 1j * np.minimum.reduceat(us.imag, voff[:-1]))
    us = us - lo[vert_isl]
    uv = np.stack([us.real, us.imag], axis=1)
    # Certify from the final UVs in the input geometry, CHUNK faces at a time: each face's alpha
    # and beta (eq. 4.19 on its corner UVs, coefficients of its 3D local frame), its signed UV
    # area; D = inf where flipped, collapsed or not finite (as metrics.conformal_distortion).
    ac, bc, unflipped = np.empty(m), np.empty(m), np.empty(m, dtype=bool)
    for i in range(0, m, CHUNK):
        f = slice(i, i + CHUNK)
        cu = us[tris[f]]
        cf = cb(f)
        ac[f] = np.abs(np.einsum("fk,fk->f", cf.conj(), cu))
        bc[f] = np.abs(np.einsum("fk,fk->f", cf, cu))
        e1, e2 = cu[:, 1] - cu[:, 0], cu[:, 2] - cu[:, 0]
        unflipped[f] = 0.5 * (e1.conj() * e2).imag > 0
    with np.errstate(invalid="ignore", divide="ignore"):
        Dc = (ac + bc) / (ac - bc)
    Dc[~(ac > bc) | ~np.isfinite(Dc) | ~unflipped] = np.inf
    flipped = np.add.reduceat((~unflipped).astype(np.int64), foff[:-1])
    maxc = np.maximum.reduceat(Dc, foff[:-1])
    cf = None
    finite = np.isfinite(Dc)
    mean = (np.bincount(face_isl, np.where(finite, A3 * Dc, 0.0), minlength=k)
            / np.maximum(np.bincount(face_isl, np.where(finite, A3, 0.0), minlength=k), 1e-300))
    ok = fit & (flipped == 0) & (maxc <= C * (1 + 1e-6))
    # Singular values at the island's own scale (UV area = 3D area), as the per-island finish
    # reports them (Lipman 2012, eqs. 4.7-4.8).
    smax = np.maximum.reduceat(ac + bc, foff[:-1])
    smin = np.minimum.reduceat(ac - bc, foff[:-1])
    seconds = (time.perf_counter() - t0) / k
    done, starts = {}, {}
    for j, isl in enumerate(islands):
        if not ok[j]:
            starts[isl.index] = u[voff[j]:voff[j + 1]] / 1.0
            continue
        mx = float(maxc[j])
        done[isl.index] = IslandResult(
            isl.index, isl.faces, isl.vertices, isl.tris, uv=uv[voff[j]:voff[j + 1]],
            status="certified",
            message=f"island {isl.index}: {len(isl.faces)} faces, max distortion {mx:.3f} <= "
                    f"{C:.4g}, 0 flipped",
            bound_requested=C, bound_certified=float(C), max_distortion=mx,
            mean_distortion=float(mean[j]), flipped=0, frames="conformal", seconds=seconds,
            distortion=Dc[foff[j]:foff[j + 1]], flags=("initial_map",),
            min_singular=float(smin[j]), max_singular=float(smax[j]),
            timings={"setup": 0.0, "solve": 0.0, "certify": 0.0})
    return done, starts


def _far_pairs(P, islands, voff):
    """Per island, two boundary vertices about half the boundary length apart (as
    ``frames._far_pair``), as union vertex ids (2k,)."""
    loops = [i.loops[0] for i in islands]
    lens = np.array([len(lp) for lp in loops])
    owner = np.repeat(np.arange(len(islands)), lens)
    lv = np.concatenate(loops) + voff[owner]
    start = np.concatenate([[0], np.cumsum(lens)[:-1]])
    nxt = np.arange(len(lv)) + 1
    last = start + lens - 1
    nxt[last] = start
    d = P.take(lv[nxt], axis=0) - P.take(lv, axis=0)    # (rows: ``take`` ~4x cheaper)
    seg = np.sqrt(d[:, 0] * d[:, 0] + d[:, 1] * d[:, 1] + d[:, 2] * d[:, 2])   # norm, same bits
    cum = np.cumsum(seg)
    before = cum - seg                      # arc length from the loop's first vertex
    before = before - before[start][owner]
    total = np.bincount(owner, seg)
    gap = np.abs(before - 0.5 * total[owner])
    order = np.lexsort((gap, owner))
    first = order[np.searchsorted(owner[order], np.arange(len(islands)))]
    return np.stack([lv[start], lv[first]], axis=1).ravel()
