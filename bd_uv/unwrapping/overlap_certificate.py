"""The one-to-one certificate of a whole unwrap: islands whose UVs lie over themselves are cut into
overlap-free pieces (no UV moves) or failed (Lipman 2012, Theorems 5.1 and 5.2)."""
import dataclasses

import numpy as np

from ..certificate import certify_islands
from ..cut import split_overlapping
from ..errors import OverlapError, SolverError


def overlap_certificate(V, F, results, face_island, corner_uv, pinned, cut=True,
                         face_groups=None, unfold=None):
    """Certify every certified island one-to-one from its final UVs (Lipman 2012, Theorems 5.1,
    5.2: simple, disjoint, rightly wound UV boundaries), and cut an island that overlaps itself
    into overlap-free pieces (``cut.split_overlapping``: no UV moves, so each piece keeps its
    distortion certificate). The pieces become islands of their own, numbered after the others;
    unpinned pieces are moved to start at (0, 0) like every island; each piece names the mesh
    edges cut (``cut_edges``) and carries the flag "cut".

    Parameters
    ----------
    pinned : set of island indices with pins (their pieces stay where the pins put them)
    cut : bool, cut an overlapping island (else it fails with OverlapError)
    unfold : callable(index) -> IslandResult or None, optional: another certified map of an
        unpinned island that overlaps itself (``unwrap_islands``: the smallest C within the one
        asked), taken instead when it is certified one-to-one from its UVs here

    Returns
    -------
    results, face_island (m,), corner_uv (m,3,2)
    certificates : tuple of Certificate (None for an island not certified), one per island, as
        ``certify_islands`` measures the returned ``corner_uv`` with each certified island's
        ``bound_certified``; None when an island was cut (its pieces were certified apart), so
        that a caller measuring the same UVs again (``layout.stored_layout``) need not
    """
    ok = np.array([r.status == "certified" for r in results], dtype=bool)
    if not ok.any():
        return results, face_island, corner_uv, (None,) * len(results)
    lab = np.where(ok[face_island], face_island, -1)
    certs = certify_islands(V, F, corner_uv, lab, np.where(ok, [
        r.bound_certified or 1.0 for r in results], 1.0))
    if all(c.overlap_free for c, good in zip(certs, ok) if good):
        kept = tuple(c if good else None for c, good in zip(certs, ok))
        return ([dataclasses.replace(r, overlap_free=bool(good)) for r, good in zip(results, ok)],
                face_island, corner_uv, kept)
    out, extra = [], []
    for r, c in zip(results, certs):
        if r.status != "certified" or c.overlap_free:
            out.append(dataclasses.replace(r, overlap_free=r.status == "certified"))
            continue
        other = _unfolded(V, F, r, corner_uv, unfold) if r.index not in pinned else None
        if other is not None:
            out.append(other)
            continue
        if not cut:
            err = OverlapError(f"island {r.index}: its UVs lie over themselves ({c.reason}); "
                               "cut it into overlap-free pieces, mark seams, or put its boundary "
                               "on a circle (boundary='circle': a bijection without new seams)",
                               r.index, r.faces)
            out.append(dataclasses.replace(r, status="failed", error=err, message=str(err),
                                           uv=None, bound_certified=None,
                                           bijective=None if r.bijective is None else False))
            corner_uv[r.faces] = np.nan
            continue
        pieces, cut_edges = split_overlapping(V, F, corner_uv, r.faces, face_groups)
        local = np.full(len(F), -1, dtype=np.int64)
        local[r.faces] = np.arange(len(r.faces))
        for n, faces in enumerate(pieces):
            rows = local[faces]
            vids, tris = np.unique(r.tris[rows], return_inverse=True)
            uv = r.uv[vids]
            if r.index not in pinned:
                uv = uv - uv.min(axis=0)
                corner_uv[faces] = uv[tris.reshape(-1, 3)]
            index = r.index if n == 0 else len(results) + len(extra)
            piece = dataclasses.replace(
                r, index=index, faces=faces, vertices=r.vertices[vids],
                tris=tris.reshape(-1, 3).astype(np.int64), uv=uv, distortion=r.distortion[rows],
                max_distortion=float(np.max(r.distortion[rows])), overlap_free=True,
                cut_edges=cut_edges, cut_from=r.index, flags=r.flags + ("cut",),
                bijective=None if r.bijective is None else False,
                message=(f"island {r.index} overlapped itself in UV and was cut into "
                         f"{len(pieces)} overlap-free pieces along {len(cut_edges)} edges "
                         f"(mark them as seams to keep the cut, or use boundary='circle' for "
                         f"one bijective island); piece {n + 1}: {len(faces)} "
                         f"faces, max distortion {np.max(r.distortion[rows]):.3f} <= "
                         f"{r.bound_certified:.4g}"))
            face_island[faces] = index
            (out if n == 0 else extra).append(piece)
    results = out + extra
    cut = np.array(["cut" in r.flags for r in results], dtype=bool)
    if cut.any():  # the pieces are certified again from their UVs, not assumed overlap-free
        lab = np.where(cut[face_island], face_island, -1)
        bounds = [r.bound_certified or 1.0 for r in results]
        for c in certify_islands(V, F, corner_uv, lab, bounds):
            if cut[c.island] and not c.certified:
                r = results[c.island]
                err = SolverError(f"island {r.index}: a piece cut from an overlapping island "
                                  f"failed its certificate ({c.reason}); mark seams there",
                                  r.index)
                results[c.island] = dataclasses.replace(r, status="failed", error=err,
                                                        message=str(err), overlap_free=False,
                                                        uv=None, bound_certified=None)
                corner_uv[r.faces] = np.nan
    return results, face_island, corner_uv, None


def _unfolded(V, F, r, corner_uv, unfold):
    """``unfold``'s map of the overlapping island r, certified one-to-one from its UVs at its
    bound and written into ``corner_uv`` (placed at (0, 0) as every unpinned island); None when
    there is none or it fails."""
    other = unfold(r.index) if unfold is not None else None
    if other is None or other.status != "certified":
        return None
    uv = other.uv - other.uv.min(axis=0)
    trial = uv[other.tris]
    lab = np.full(len(F), -1, dtype=np.int64)
    lab[r.faces] = 0
    whole = np.full_like(corner_uv, np.nan)
    whole[r.faces] = trial
    c = certify_islands(V, F, whole, lab, [other.bound_certified])[0]
    if not (c.certified and c.overlap_free):
        return None
    corner_uv[r.faces] = trial
    return dataclasses.replace(other, uv=uv, overlap_free=True)
