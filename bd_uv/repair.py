"""Real meshes as they come: the pieces of a messy mesh that can be unwrapped, and what cannot.

Assets made by others carry non-manifold (bow-tie) vertices, edges shared by three or more faces,
parts oriented against their neighbours, duplicate faces and zero-area faces. ``mesh.islands``
refuses an island holding any of them (``NonManifoldError`` and the like), which is right for the
explicit "marked seams" mode; ``repair_mesh`` instead returns a mesh every piece of which is a
manifold, consistently oriented surface:

- zero-area faces and faces with a non-finite corner are left out: no map of them can be
  certified;
- of faces on the same three vertices in the same cyclic order, the first is kept and the others
  are left out of the solve (``twin``: they get its UVs afterwards);
- every vertex is split into one vertex per fan of corners, where corners are joined only across
  an edge of exactly two faces that orient it oppositely. This splits a bow-tie vertex per fan,
  and cuts an edge of three or more faces and an edge between two faces oriented alike (each
  differently oriented part becomes a part of its own) like a seam;
- a face on the three vertices of an earlier face in the reverse order (the back of a surface
  modelled double-sided, as game and CAD exports often are) is glued only to other such faces:
  the backs make a surface of their own, unwrapped beside the front (otherwise every edge of a
  double-sided mesh has four faces and each face became an island of its own).

A clean mesh comes back unchanged (same vertex ids, same faces).
"""
from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp
from scipy.sparse.csgraph import connected_components

from .geometry import face_areas
from .mesh import (DEGENERATE_RATIO, TOO_LARGE, check_arrays, measurable,
                   thinner_than_precision)


@dataclass(frozen=True)
class Repair:
    """A messy mesh made solvable (:func:`repair_mesh`).

    Attributes
    ----------
    V : (n2,3) float64, the input vertices, then one copy per extra fan of a split vertex
    F : (k,3) int64, the faces to solve, in ids of ``V``
    faces : (k,) int64, input face of each row of ``F``
    vertex_source : (n2,) int64, input vertex of each vertex of ``V``
    twin : (m,) int64, for an input face left out as a duplicate the face it duplicates (a
        solved one); -1 otherwise
    zero_area : (z,) int64, input faces of zero area (not solved)
    non_finite : (q,) int64, input faces with a NaN or infinite corner, or one beyond
        ``mesh.MEASURABLE`` (not solved)
    split_vertices : (b,) int64, input vertices split into one vertex per fan
    nonmanifold_edges : (e1,2) int64, input vertex pairs of edges of three or more faces (cut)
    orientation_edges : (e2,2) int64, input vertex pairs of edges whose two faces are oriented
        alike (cut: each differently oriented part is unwrapped on its own)
    back_faces : (b,) int64, input faces on an earlier solved face's vertices in reverse order
        (a double-sided surface's back: glued only to each other)
    """

    V: np.ndarray
    F: np.ndarray
    faces: np.ndarray
    vertex_source: np.ndarray
    twin: np.ndarray
    zero_area: np.ndarray
    non_finite: np.ndarray
    split_vertices: np.ndarray
    nonmanifold_edges: np.ndarray
    orientation_edges: np.ndarray
    back_faces: np.ndarray

    @property
    def changed(self):
        """Whether anything was split, cut or left out."""
        return bool(len(self.zero_area) or len(self.non_finite) or (self.twin >= 0).any()
                    or len(self.split_vertices)
                    or len(self.nonmanifold_edges) or len(self.orientation_edges)
                    or len(self.back_faces))

    def seams(self, pairs):
        """The (s,2) input vertex pairs ``pairs`` as edges of ``F`` (every copy of a split one).

        Returns
        -------
        (t,2) int64, vertex pairs in ids of ``V``
        """
        if pairs is None or not len(pairs):
            return np.zeros((0, 2), dtype=np.int64)
        pairs = np.asarray(pairs, dtype=np.int64).reshape(-1, 2)
        n = int(max(self.vertex_source.max(initial=0), pairs.max(initial=0))) + 1
        a, b = self.F.ravel(), np.roll(self.F, -1, axis=1).ravel()
        sa, sb = self.vertex_source[a], self.vertex_source[b]
        key = np.minimum(sa, sb) * n + np.maximum(sa, sb)
        want = np.minimum(pairs[:, 0], pairs[:, 1]) * n + np.maximum(pairs[:, 0], pairs[:, 1])
        hit = np.isin(key, want)
        out = np.stack([np.minimum(a[hit], b[hit]), np.maximum(a[hit], b[hit])], axis=1)
        return np.unique(out, axis=0) if len(out) else out.reshape(0, 2)

    def notes(self, indices=True, count=len):
        """One sentence per kind of defect found and what was done about it (list of str).

        With ``indices=False`` (the Blender operator, whose users count polygons, not these
        triangles) the sentences give counts only, and zero-area faces, which the result names
        as a failed island, are left out; ``count(faces)`` counts input faces (the operator:
        the polygons they belong to)."""
        out = []
        dup = np.flatnonzero(self.twin >= 0)

        def which(kind, ids):
            return f" ({kind} {ids})" if indices else ""
        if len(self.split_vertices):
            out.append(f"{len(self.split_vertices)} non-manifold vertex(es) split into one "
                       f"vertex per fan" + which("vertices", _some(self.split_vertices)))
        if len(self.nonmanifold_edges):
            out.append(f"{len(self.nonmanifold_edges)} edge(s) shared by three or more faces cut "
                       f"as seams" + which("edges", _pairs(self.nonmanifold_edges)))
        if len(self.orientation_edges):
            out.append(f"{len(self.orientation_edges)} edge(s) between faces oriented against "
                       f"each other cut as seams: each oriented part is its own chart"
                       + which("edges", _pairs(self.orientation_edges)))
        if len(self.back_faces):
            out.append(f"{count(self.back_faces)} face(s) on an earlier face's vertices in reverse "
                       f"order (a double-sided surface's back) unwrapped as a surface of their own"
                       + which("faces", _some(self.back_faces)))
        if len(dup):
            out.append(f"{count(dup)} duplicate face(s) left out of the solve, given their twin's "
                       f"UVs" + which("faces", _some(dup)))
        if len(self.zero_area) and indices:
            out.append(f"{len(self.zero_area)} zero-area face(s) cannot be certified: their UVs "
                       f"are left as they were (faces {_some(self.zero_area)})")
        if len(self.non_finite) and indices:
            out.append(f"{len(self.non_finite)} face(s) with NaN or infinite coordinates, or "
                       f"{TOO_LARGE}, cannot be certified: their UVs are left as they were (faces "
                       f"{_some(self.non_finite)})")
        return out


def _some(idx, k=8):
    idx = np.asarray(idx).ravel()
    s = ", ".join(str(int(i)) for i in idx[:k])
    return s + (f", ... ({len(idx)} in all)" if len(idx) > k else "")


def _pairs(pairs, k=4):
    s = ", ".join(f"{int(a)}-{int(b)}" for a, b in np.asarray(pairs)[:k])
    return s + (f", ... ({len(pairs)} in all)" if len(pairs) > k else "")


def zero_area_faces(V, F, precision=None):
    """(m,) bool: faces with finite corners and twice their area below ``DEGENERATE_RATIO``
    times their longest edge squared (``mesh.islands``' test). With ``precision``, the float
    type the positions were stored in (``np.float32``: glTF, USD, Blender), also the faces whose
    height (twice the area over the longest edge) is below one step of that type at their
    largest coordinate: three points that precision cannot tell from a line (OpenChessSet's
    bishops hold hundreds), whose angles, and so whose distortion, are rounding
    noise, and whose UVs no float32 store keeps apart."""
    P = V[F]
    finite = measurable(P)
    # non-finite corners (refused by name elsewhere) give NaN here, not numpy warnings
    with np.errstate(invalid="ignore", over="ignore", divide="ignore"):
        A = face_areas(V, F)
        lmax2 = np.max(np.sum((P - np.roll(P, -1, axis=1)) ** 2, axis=2), axis=1)
        zero = ~(2 * A > DEGENERATE_RATIO * lmax2)
    zero |= thinner_than_precision(P, A, lmax2, precision)
    return zero & finite


def flat_at_precision(V, F, precision):
    """(m,) bool: the faces ``precision`` (the float type the positions were stored in) cannot
    tell from a line though float64 can (``zero_area_faces``); None for float64, for no such
    face, and for arrays the unwrap refuses anyway (non-finite positions, bad indices)."""
    if precision is None or np.dtype(precision) == np.float64:
        return None
    try:
        V, F = np.asarray(V, np.float64), np.asarray(F, np.int64)
        with np.errstate(all="ignore"):
            flat = zero_area_faces(V, F, precision) & ~zero_area_faces(V, F)
    except (ValueError, IndexError, TypeError):
        return None
    return flat if flat.any() else None


def side_by_side(F, faces):
    """True when two of ``faces`` ((m,) bool) share an edge: faces ``flat_at_precision`` finds
    side by side refuse their island as stored at any stretch (OpenChessSet's bishops: 608 in
    strips), where one alone is often certified as stored (the storage headroom's stretch)."""
    f = np.asarray(F, np.int64)[faces]
    e = np.sort(f[:, [0, 1, 1, 2, 2, 0]].reshape(-1, 2), axis=1)
    return len(np.unique(e, axis=0)) < len(e)


def stored_precision(V, F, precision):
    """``precision`` when faces it cannot tell from a line lie side by side, else None: what
    ``bd_uv.unwrap(seams="needed", precision=)`` and ``repair_mesh`` take to leave them out as
    zero-area from the start (the Blender operator; ``batch.unwrap_job``)."""
    flat = flat_at_precision(V, F, precision)
    return precision if flat is not None and side_by_side(F, flat) else None


def duplicate_twins(F, skip=None):
    """(m,) int64: for each face on the same three vertices, in the same cyclic order, as an
    earlier face, that face's index; -1 otherwise. Faces in ``skip`` (m,) bool are ignored."""
    m = len(F)
    twin = np.full(m, -1, dtype=np.int64)
    cand = np.arange(m) if skip is None else np.flatnonzero(~skip)
    if not len(cand):
        return twin
    G = F[cand]
    r = np.argmin(G, axis=1)                       # rotate to start at the smallest vertex
    G = np.take_along_axis(G, (r[:, None] + np.arange(3)) % 3, axis=1)
    _, first, inv = np.unique(G, axis=0, return_index=True, return_inverse=True)
    inv = inv.ravel()
    rep = cand[first[inv]]
    dup = rep != cand
    twin[cand[dup]] = rep[dup]
    return twin


def twin_corners(F, faces, twins):
    """(k,3) int64: for each face of ``faces`` (k,), the corner of its twin in ``twins`` (k,)
    holding the same vertex as each of its corners (the two share their three vertices)."""
    F = np.asarray(F, dtype=np.int64)
    return np.argmax(F[faces][:, :, None] == F[twins][:, None, :], axis=2)


def repair_mesh(V, F, precision=None):
    """Split, cut and leave out what keeps a mesh from being unwrapped piece by piece.

    Parameters
    ----------
    V : (n,3) float array
    F : (m,3) int array
    precision : float type the positions were stored in, optional (``zero_area_faces``)

    Returns
    -------
    Repair

    Raises
    ------
    InvalidMeshError for arrays that are not a mesh (``mesh.check_arrays``)
    """
    V, F = check_arrays(V, F)
    n = len(V)
    zero = zero_area_faces(V, F, precision)
    bad = ~measurable(V[F])
    twin = duplicate_twins(F, skip=zero | bad)
    faces = np.flatnonzero(~zero & ~bad & (twin < 0))
    Fk = F[faces]
    k = len(Fk)
    back = _reversed_repeats(Fk)
    # Half-edge h = 3 f + c runs from Fk[f, c] to Fk[f, c + 1]; its key names the edge and the
    # side (front 0, back 1) of its face, so that only faces of one side are glued.
    src = Fk.ravel()
    dst = np.roll(Fk, -1, axis=1).ravel()
    side = np.repeat(back, 3).astype(np.int64)
    key = (np.minimum(src, dst) * n + np.maximum(src, dst)) * 2 + side
    uniq, inv, count = np.unique(key, return_inverse=True, return_counts=True)
    inv = inv.ravel()
    order = np.argsort(inv, kind="stable")
    first = np.searchsorted(inv[order], np.arange(len(uniq)))
    two = np.flatnonzero(count == 2)
    h1, h2 = order[first[two]], order[first[two] + 1]
    opposite = src[h1] == dst[h2]
    nxt = lambda h: h - h % 3 + (h % 3 + 1) % 3
    # Corners glued across an edge of two faces oriented oppositely: the corner of src[h] is h.
    g1, g2 = h1[opposite], h2[opposite]
    rows = np.concatenate([g1, nxt(g1)])
    cols = np.concatenate([nxt(g2), g2])
    adj = sp.coo_array((np.ones(len(rows)), (rows, cols)), shape=(3 * k, 3 * k))
    _, fan = connected_components(adj, directed=False)
    # One vertex per (input vertex, fan): the first fan of a vertex keeps its id. A vertex is
    # named split when one side holds two fans of it (front and back apart are no defect).
    pairs, pinv = np.unique(np.stack([src, side, fan], axis=1), axis=0, return_inverse=True)
    pinv = pinv.ravel()
    again = np.r_[False, pairs[1:, 0] == pairs[:-1, 0]]
    split = np.flatnonzero(np.r_[False, (pairs[1:, :2] == pairs[:-1, :2]).all(axis=1)])
    extra = np.flatnonzero(again)
    new_id = pairs[:, 0].copy()
    new_id[extra] = n + np.arange(len(extra))
    vertex_source = np.concatenate([np.arange(n), pairs[extra, 0]])
    F2 = new_id[pinv].reshape(k, 3) if k else np.zeros((0, 3), dtype=np.int64)
    V2 = V[vertex_source]
    e = uniq // 2
    ends = np.stack([e // n, e % n], axis=1) if len(uniq) else np.zeros((0, 2), np.int64)
    return Repair(V2, F2.astype(np.int64), faces.astype(np.int64), vertex_source.astype(np.int64),
                  twin, np.flatnonzero(zero).astype(np.int64),
                  np.flatnonzero(bad).astype(np.int64),
                  np.unique(pairs[split, 0]).astype(np.int64), _rows(ends[count >= 3]),
                  _rows(ends[two[~opposite]]), faces[back].astype(np.int64))


def _reversed_repeats(Fk):
    """(k,) bool: faces on the same three vertices as an earlier face of ``Fk`` (k,3) (with no
    two in the same cyclic order, ``duplicate_twins``, so in the reverse order)."""
    if not len(Fk):
        return np.zeros(0, dtype=bool)
    _, first, inv = np.unique(np.sort(Fk, axis=1), axis=0, return_index=True,
                              return_inverse=True)
    return first[inv.ravel()] != np.arange(len(Fk))


def _rows(pairs):
    """The distinct rows of (e,2) ``pairs`` (an edge cut on both sides is named once)."""
    return np.unique(pairs, axis=0) if len(pairs) else pairs.reshape(0, 2)
