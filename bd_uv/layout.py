"""From an unwrap to the UVs a file stores: cut overlapping islands, pack, re-certify as stored.

The one write path of the command line and the batch tool (and the pattern the Blender operator and
script follow with their own storage): every island is certified by :func:`certify_islands` from
the UVs exactly as they will be stored, and only islands that pass are written. The report entries,
the summary line and the PNG caption all read the same :class:`Certificate` objects.
"""
from dataclasses import dataclass

import numpy as np

from .certificate import certificate_totals, certify_islands
from .cut import split_overlapping
from .overlap import layout_overlaps
from .uv_boundary import exact_bits, row_ids
from .pack import MARGIN, island_boxes, pack_islands
from .repair import twin_corners

#: rounds of cutting pieces whose boundary crosses itself once stored (each re-packs: a new
#: layout rounds other near-touching boundaries differently)
RECUT_ROUNDS = 4


@dataclass(frozen=True)
class Layout:
    """The UVs as stored and what they prove.

    Attributes
    ----------
    corner_uv : (m,3,2) float64, the stored UVs; NaN on faces not written
    face_island : (m,) int64, stored island of each face (-1: not written)
    source : (k,) int64, the unwrap island each stored island comes from
    certificates : list of Certificate, one per stored island, measured as stored (failed ones
        included: their faces are not written)
    unwrapped : list of Certificate, one per unwrap island, measured on the unwrap's own UVs
        (None for islands the unwrap did not certify)
    cut_edges : list of (c,2) int64 per unwrap island, the edges cut to remove its overlap
    overlaps : (p,2) int64, pairs of written stored islands that overlap each other
    packed : bool
    pack : dict or None, with the atlas packer (``pack_options``): its figures measured on the
        stored UVs (``seconds`` of packing alone, ``coverage``, ``resolution``, ``padding_px``,
        ``least_gap_px``, ``tiles``, ... from :class:`bd_uv.packing.LayoutCertificate`)
    """
    corner_uv: np.ndarray
    face_island: np.ndarray
    source: np.ndarray
    certificates: list
    unwrapped: list
    cut_edges: list
    overlaps: np.ndarray
    packed: bool
    pack: dict = None

    def vertex_uv(self, F, fill=None):
        """One ``vt`` per (island, vertex, UV) of the written faces, for :func:`write_obj`.

        ``fill`` (m,) bool, optional: faces not written (zero-area faces: no shape to map or
        certify) whose corners take the ``vt`` of the same vertex in some written face, so they
        add no seam and stay (near) degenerate in UV; a corner whose vertex no written face has
        at (0, 0), as a scene writes it.

        Returns
        -------
        uv : (K,2) float64
        F_uv : (m,3) int64, -1 on faces not written
        """
        F = np.asarray(F, dtype=np.int64)
        written = self.face_island >= 0
        F_uv = np.full(F.shape, -1, dtype=np.int64)
        if not written.any():
            return np.zeros((0, 2)), F_uv
        uv = self.corner_uv[written].reshape(-1, 2)
        isl = np.repeat(self.face_island[written], 3)
        ids = row_ids(isl, F[written].ravel(), exact_bits(uv[:, 0]), exact_bits(uv[:, 1]))
        table = np.zeros((int(ids.max()) + 1, 2))
        table[ids] = uv
        F_uv[written] = ids.reshape(-1, 3)
        if fill is not None and (fill & ~written).any():
            of_vertex = np.full(int(F.max()) + 1, -1, dtype=np.int64)
            of_vertex[F[written].ravel()] = ids
            fill = np.flatnonzero(np.asarray(fill, bool) & ~written)
            got = of_vertex[F[fill]]
            if (got < 0).any():           # a vertex of zero-area faces only: at (0, 0)
                got[got < 0] = len(table)
                table = np.vstack([table, [0.0, 0.0]])
            F_uv[fill] = got
        return table, F_uv

    def totals(self):
        """certificate_totals over the stored islands, plus cut and overlap counts."""
        t = certificate_totals(self.certificates)
        t.update(overlapping_unwrapped=sum(c is not None and not c.overlap_free
                                           for c in self.unwrapped),
                 cut_islands=sum(len(c) > 0 for c in self.cut_edges),
                 cut_edges=int(sum(len(c) for c in self.cut_edges)),
                 layout_overlaps=int(len(self.overlaps)))
        return t

    def island_entries(self, res):
        """The report's per-island entries: the unwrap's own summary, with the figures replaced by
        what the stored UVs measure, and ``overlap_free``, ``crossings``, ``pieces``, ``cut_edges``
        added."""
        entries = []
        for r in res.islands:
            e = r.summary()
            mine = [c for c, s in zip(self.certificates, self.source) if s == r.index]
            before = self.unwrapped[r.index]
            e["crossings"] = before.crossings if before is not None else None
            if len(self.cut_edges[r.index]) or e["cut_edges"] is None:  # else unwrap() cut it
                e["cut_edges"] = self.cut_edges[r.index].tolist()
            e["pieces"] = len(mine)
            if not mine:  # the unwrap failed: nothing stored
                e["overlap_free"] = None
                entries.append(e)
                continue
            t = certificate_totals(mine)
            e["overlap_free"] = all(c.overlap_free for c in mine)
            e["flipped"] = int(sum(c.flipped for c in mine))
            e["stored"] = [c.summary() for c in mine]
            if t["certified"] == len(mine):
                e.update(max_distortion=t["max_distortion"], mean_distortion=t["mean_distortion"])
            else:
                bad = [c for c in mine if not c.certified]
                # the pieces that pass are written (``stored_layout``): say which part is not
                what = ("not written" if len(bad) == len(mine) else
                        f"{len(mine) - len(bad)} of its {len(mine)} pieces written, "
                        f"{len(bad)} not")
                e.update(status="failed", error="NotCertifiedAsStored", bound_certified=None,
                         bijective=None if e["bijective"] is None else False,
                         max_distortion=max(c.max_distortion for c in mine),
                         message=f"island {r.index}: {what}, the UVs as stored fail "
                                 f"certification: {bad[0].reason}")
                if not np.isfinite(e["max_distortion"]):
                    e["max_distortion"] = None
            entries.append(e)
        return entries

    def caption(self, name, method, seconds):
        """The PNG caption, from the stored certificates (area-weighted mean)."""
        t = self.totals()
        head = f"{name}: BD-{method.upper()}"
        if not t["certified"]:
            return f"{head}, no island certified"
        extra = ""
        if t["cut_islands"]:
            extra += f", {t['cut_islands']} island(s) cut ({t['cut_edges']} edges)"
        if t["layout_overlaps"]:
            extra += f", {t['layout_overlaps']} overlapping island pair(s)"
        if self.pack:
            p = self.pack
            gap = "" if p["least_gap_px"] is None else f", least gap {p['least_gap_px']:.2f} px"
            extra += (f", coverage {p['coverage']:.3f} at {p['resolution']} px{gap} (padding "
                      f"{p['padding_px']:g} px{'' if p['certified'] else ', NOT met'})")
        return (f"{head}, {t['certified']}/{t['islands']} islands, {t['faces']} faces, max "
                f"distortion {t['max_distortion']:.3f} <= {t['bound']:.3g}, mean "
                f"{t['mean_distortion']:.3f}, 0 flipped, overlap-free{extra}, {seconds:.2f} s")


def stored_layout(V, F, res, pack=True, cut=True, margin=MARGIN, dtype=np.float64,
                  pack_options=None, face_labels=None, face_groups=None, v_down=False):
    """Turn an :class:`UnwrapResult` into the UVs to store, and certify them as stored.

    1. islands the unwrap certified are checked for self-overlap; with ``cut`` an overlapping one
       is cut into overlap-free pieces (:func:`split_overlapping`, UVs unchanged);
    2. with ``pack`` all islands go into the unit square: by their outlines with
       ``pack_options`` (:func:`bd_uv.packing.pack_islands`), else on shelves of boxes
       (:func:`pack_islands`, ``margin``); without ``pack`` each cut piece is moved to (0, 0) like
       the unwrap's islands;
    3. the UVs are rounded to ``dtype`` (float32 in Blender; the OBJ writer keeps float64) and every
       stored island is certified from them; islands that fail are not written.

    Parameters
    ----------
    V : (n,3) float array
    F : (m,3) int array
    res : UnwrapResult
    pack, cut : bool
    margin : float, shelf packing margin in the unit square (without ``pack_options``)
    dtype : numpy dtype the UVs are stored in
    pack_options : bd_uv.packing.PackOptions, optional: pack with the atlas packer; its layout
        certificate (on the stored, written islands) goes into ``Layout.pack``
    face_labels : dict, optional: each face's "material" and "object" (``Mesh.labels``), for
        ``pack_options.group``
    face_groups : (m,) int array, optional, the polygon of each face: a cut never splits one
        (a scene stores one UV per face-vertex, Blender one per loop)
    v_down : bool, the format stores 1 - v (glTF): the UVs are certified as it holds them
        (:func:`as_stored`)

    Returns
    -------
    Layout
    """
    V = np.asarray(V, dtype=np.float64)
    F = np.asarray(F, dtype=np.int64)
    m = len(F)
    n = len(res.islands)
    ok = np.array([r.status == "certified" for r in res.islands], dtype=bool)
    bounds = np.array([r.bound_certified if r.status == "certified" else np.nan
                       for r in res.islands], dtype=np.float64)
    lab = np.where(ok[res.face_island], res.face_island, -1) if n else np.full(m, -1)
    dup = np.zeros(m, dtype=bool) if res.duplicate_of is None else res.duplicate_of >= 0
    lab[dup] = -1  # a duplicate face is stored with its twin's UVs, not certified twice
    uv = np.asarray(res.corner_uv, dtype=np.float64)
    before = res.certificates
    if before is None or len(before) != n:  # the unwrap did not keep them: measure
        before = certify_islands(V, F, uv, lab, np.where(ok, bounds, 1.0))
    unwrapped = [c if ok[i] else None for i, c in enumerate(before)]
    new = np.full(m, -1, dtype=np.int64)
    source, cuts, moved = [], [], []
    for i in range(n):  # per island
        faces = np.flatnonzero(lab == i)
        pieces, cut_edges = ([faces] if ok[i] else []), np.zeros((0, 2), dtype=np.int64)
        if ok[i] and cut and not before[i].overlap_free:
            pieces, cut_edges = split_overlapping(V, F, uv, faces, face_groups)
        for p in pieces:
            new[p] = len(source)
            source.append(i)
            moved.append(len(pieces) > 1)
        cuts.append(cut_edges)
    source = np.asarray(source, dtype=np.int64)
    unpacked = uv
    for again in (True,) * RECUT_ROUNDS + (False,):   # more rounds only for pieces cut as stored
        uv, packed = _place(V, F, unpacked, new, source, moved, pack, pack_options, margin,
                            face_labels)
        stored = as_stored(uv, dtype, v_down)
        certs = certify_islands(V, F, stored, new, bounds[source] if len(source) else [])
        # Rounding can make a boundary that touched itself in float64 cross (a piece of the
        # ASWF's OpenChessSet pawn, of Khronos' BrainStem): cut such pieces again, on their
        # UVs as stored, and place everything again.
        recut = [j for j, c in enumerate(certs) if again and cut and not c.overlap_free
                 and np.isfinite(stored[new == j]).all()]
        grown = False
        for j in recut:   # per piece that crosses itself as stored
            pieces, cut_edges = split_overlapping(V, F, stored, np.flatnonzero(new == j),
                                                  face_groups)
            for p in pieces[1:]:
                new[p] = len(source)
                source = np.append(source, source[j])
                moved.append(True)
                grown = True
            moved[j] = moved[j] or len(pieces) > 1
            if len(cut_edges):
                cuts[source[j]] = np.concatenate([cuts[source[j]], cut_edges])
        if not grown:
            break
    passed = np.array([c.certified for c in certs], dtype=bool)
    written = np.where(new >= 0, passed[np.maximum(new, 0)] if len(passed) else False, False)
    face_island = np.where(written, new, -1)
    stored[~written] = np.nan
    overlaps = layout_overlaps(stored, face_island, F) if written.any() else np.zeros((0, 2), int)
    # the layout certificate of the written islands (duplicate faces, copies of their twins'
    # UVs, are added after it)
    report = _pack_report(V, F, stored, face_island, packed) if packed is not None else None
    if dup.any():
        d = np.flatnonzero(dup)
        tw = res.duplicate_of[d]
        stored[d] = np.take_along_axis(stored[tw], twin_corners(F, d, tw)[:, :, None], axis=1)
        face_island[d] = face_island[tw]
    return Layout(stored, face_island, source, certs, unwrapped, cuts, overlaps, bool(pack),
                  report)


# float32's step in [0.5, 1): v stored on this grid has 1 - v exact in float32 too
V_GRID = 2.0 ** -24


def as_stored(uv, dtype, v_down=False):
    """The UVs (..., 2) float64 as ``dtype`` stores them, back in float64. With ``v_down`` (the
    format stores 1 - v: glTF, whose v runs downwards) in float32, v is first put on the grid of
    ``V_GRID`` (float32's own step in [0.5, 1)), so that 1 - v is exact in float32 as well: the
    UVs certified are those the file holds. (Before, glTF's 1 - v rounded otherwise and could
    flip a thin face certified as float32: the scenes fuzz contract's sliver, seed 22109, was
    refused whole where the sliver should have been left out.)"""
    if not v_down or np.dtype(dtype) != np.float32:
        return np.asarray(uv).astype(dtype).astype(np.float64)
    out = np.array(uv, dtype=np.float64, copy=True)
    out[..., 1] = np.round(out[..., 1] / V_GRID) * V_GRID
    return out.astype(np.float32).astype(np.float64)


def _place(V, F, uv, new, source, moved, pack, pack_options, margin, face_labels):
    """The pieces ``new`` of ``uv`` placed: (UVs, Packed or None): by the atlas packer with
    ``pack_options``, on shelves (``pack``), or each moved piece to (0, 0)."""
    if pack and pack_options is not None and len(source):
        from .packing import pack_islands as pack_atlas
        packed = pack_atlas(V, F, uv, new, pack_options, face_labels=face_labels)
        return packed.corner_uv, packed
    if pack:
        return pack_islands(uv, new, margin), None
    if any(moved):
        lo, _ = island_boxes(uv, new, len(source))
        shift = np.where(np.asarray(moved)[:, None], lo, 0.0)
        sel = new >= 0
        uv = uv.copy()
        uv[sel] -= shift[new[sel]][:, None, :]
    return uv, None


def _pack_report(V, F, stored, face_island, packed):
    """The ``pack`` report object: the layout certificate of the written islands as stored."""
    from .packing import layout_certificate
    o = packed.options
    cert = layout_certificate(V, F, stored, face_island, packed.tile, o.resolution, o.padding_px)
    return pack_summary(packed, cert)


def pack_summary(packed, cert):
    """The ``pack`` report object of a packing (``Packed``) and its layout certificate."""
    o = packed.options
    return dict(seconds=round(packed.seconds, 4), **cert.summary(),
                texel_density=packed.texel_density, rotate=o.rotate, group=o.group,
                solves=packed.solves)
