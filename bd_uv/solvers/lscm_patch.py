"""A pinned LSCM system (``lscm._lscm_system`` with the edges known) whose faces change a few at a
time: its values patched where the faces rebuilt since the last system touch it, the rest kept.

The angle start (``unwrapping.angle_start``) solves the conformal map of one disk with the same
pins up to four times, each time with a few faces rebuilt (homer's 3,521-face patch: 5, 13 and 13
of them). Every value of the system is a sum of the faces' terms at one place: a vertex's
diagonal (its corners' terms in corner order: ``np.bincount``'s), an edge's real part (its one
or two sides', the first plus the second), a boundary edge's imaginary part (its side's). Here
every place a rebuilt face touches is summed again from all the terms at that place, in the same
order, and written where ``_lscm_system`` writes it; every other value is the last system's: the
same triplets, right-hand side and bits as ``_lscm_system`` of the new faces, without its
assembly over every face (homer's patch: ~0.15 against ~0.6 ms a solve). A rebuilt face with a
pinned corner moves the right-hand side: then the system is assembled anew.
"""
import numpy as np

from .lscm import _lscm_system

__all__ = ["PatchedLSCM"]


class PatchedLSCM:
    """``_lscm_system(geom.cbw(), geom.cb, tris, n, idx, val, sides, triplets=True)``, kept to
    be patched (``rebuilt``).

    Parameters
    ----------
    geom : ``lscm.FaceGeometry`` of the faces ``tris`` (m,3) into n vertices
    idx, val : the pinned vertices (int64) and their values; sides : ``_lscm_system``'s (the
        interior edges' two sides s1 < s2, the boundary's sides)
    """

    def __init__(self, geom, tris, n, idx, val, sides):
        self.tris, self.n, self.idx, self.val, self.sides = tris, n, idx, val, sides
        self._build(geom)

    def _build(self, geom):
        """The system assembled afresh from ``geom`` (every face's geometry now)."""
        tris, n, idx, val, sides = self.tris, self.n, self.idx, self.val, self.sides
        self._system = _lscm_system(geom.cbw(), geom.cb, tris, n, idx, val, sides,
                                    triplets=True)
        self._u = self._system[2].copy()        # (the caller writes its map into the copy)
        self._places = None                     # made at the first patch

    def system(self):
        """``_lscm_system``'s answer (``lscm.Upper``, rhs, u, free) of the current faces (u a
        new array each call)."""
        A, rhs, _, free = self._system
        return A, rhs, self._u.copy(), free

    def rebuilt(self, geom, faces):
        """The faces ``faces`` (int64 array) rebuilt since the last system, ``geom`` every
        face's ``FaceGeometry`` now: the system patched (returns ``system()``)."""
        if len(faces) and self._places is None:
            self._places = self._made(geom)
        if len(faces) and self._places["pin_faces"].take(faces).any():
            self._build(geom)
        elif len(faces):
            self._patch(geom, faces)
        return self.system()

    def _made(self, geom):
        """Each corner's and side's terms (of every face as ``geom`` has it now: the faces
        rebuilt since are patched over again, the same numbers) and each place's slots among
        the triplets ``[diag u, edges u, diag v, edges v, -im, im]`` (``_lscm_system``'s)."""
        tris, n = self.tris, self.n
        pinned = np.zeros(n, dtype=bool)
        pinned[self.idx] = True
        s1, s2, sb = self.sides
        ni, nb = len(s1), len(sb)
        lo = np.minimum(tris, tris[:, [1, 2, 0]]).ravel()
        hi = np.maximum(tris, tris[:, [1, 2, 0]]).ravel()
        ends = np.concatenate([s1, sb])
        on = ~pinned.take(lo.take(ends)) & ~pinned.take(hi.take(ends))
        nf, n_on = n - int(np.count_nonzero(pinned)), int(np.count_nonzero(on))
        side_edge = np.empty(3 * len(tris), dtype=np.int64)
        side_edge[s1] = np.arange(ni)
        side_edge[s2] = np.arange(ni)
        side_edge[sb] = ni + np.arange(nb)
        places = {
            "pin_faces": pinned.take(tris).any(axis=1),
            "vertex": np.where(pinned, -1, np.cumsum(~pinned) - 1),
            "edge": np.where(on, np.cumsum(on) - 1, -1),
            "rim": np.where(on[ni:], np.cumsum(on[ni:]) - 1, -1),
            "side_edge": side_edge,
            # the slots' starts: edges u, diag v, edges v, -im, im
            "at": (nf, nf + n_on, 2 * nf + n_on, 2 * nf + 2 * n_on,
                   2 * nf + 2 * n_on + int(np.count_nonzero(on[ni:]))),
        }
        self._d, self._re, self._im = self._terms(geom, slice(None))
        return places

    def _terms(self, geom, faces):
        """The faces' corners' diagonal terms and sides' real and signed imaginary terms,
        (3f,) each in corner order (``_lscm_system``'s arithmetic, ``FaceGeometry.cbw``'s)."""
        tris = self.tris[faces]
        cb = geom.cb[faces]
        cbw = geom.zarea[faces][:, None] * cb.conj()
        hjk = (cbw * cb[:, [1, 2, 0]]).ravel()
        im = np.where((tris < tris[:, [1, 2, 0]]).ravel(), hjk.imag, -hjk.imag)
        return (cbw * cb).real.ravel(), hjk.real.copy(), im

    def _patch(self, geom, faces):
        p = self._places
        at_u, at_dv, at_ev, at_im, at_im2 = p["at"]
        corners = (3 * faces[:, None] + np.arange(3)).ravel()
        self._d[corners], self._re[corners], self._im[corners] = self._terms(geom, faces)
        A, rhs, _, free = self._system
        vals = A.vals.copy()
        # the diagonal of each vertex of the faces: all its corners' terms, in corner order
        flat = self.tris.ravel()
        touched = np.zeros(self.n, dtype=bool)
        touched[flat.take(corners)] = True
        at = touched.take(flat).nonzero()[0]
        diag = np.bincount(flat.take(at), self._d.take(at), self.n)
        v = touched.nonzero()[0]
        slot = p["vertex"].take(v)
        v, slot = v[slot >= 0], slot[slot >= 0]
        vals[slot] = vals[at_dv + slot] = diag.take(v)
        # the edges of their sides: an interior edge's two sides (first plus second), a
        # boundary edge's one (its real part, and its imaginary part both ways)
        s1, s2, sb = self.sides
        ni = len(s1)
        e = np.unique(p["side_edge"].take(corners))
        inner, outer = e[e < ni], e[e >= ni] - ni
        re = np.concatenate([self._re.take(s1.take(inner)) + self._re.take(s2.take(inner)),
                             self._re.take(sb.take(outer))])
        slot = p["edge"].take(np.concatenate([inner, ni + outer]))
        keep = slot >= 0
        vals[at_u + slot[keep]] = vals[at_ev + slot[keep]] = re[keep]
        slot = p["rim"].take(outer)
        keep = slot >= 0
        im = self._im.take(sb.take(outer))[keep]
        vals[at_im + slot[keep]] = -im
        vals[at_im2 + slot[keep]] = im
        self._system = (type(A)(A.rows, A.cols, vals, A.n), rhs, None, free)
