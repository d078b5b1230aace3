"""The certificate of one live frame, from its own coordinates (Lipman 2012, eq. 4.9, Thms 5.1-5.2).

A frame of a live session is a map ``U`` (n,2) of one island whose triangles and rest shape never
change during the session, so everything but the coordinates is computed once: the per-face
gradient operators of the rest shape, the boundary half-edges and their loops. A frame is
certified when

1. no face is flipped and every face's conformal distortion ``(|a|+|b|)/(|a|-|b|)`` against the
   rest shape is at most C (vectorised closed-form 2x2 singular values);
2. its UV boundary is simple: no two boundary segments meet other than consecutive ones at their
   shared end, and every loop has the faces on the side of winding number 1 (``overlap``). For a
   flip-free map this is one-to-one (Theorems 5.1 and 5.2).

Step 2 is incremental: a frame is compared with a frame already certified, and only the pairs of
segments of which at least one moved are tested (a spatial index over the current segments,
queried with the moved ones). Pairs of unmoved segments did not meet in the certified frame and
still do not.
"""
from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp

from ..energies import jacobian_operators
from ..overlap import _loops, _winding_ok, crossing_pairs
from ..uv_boundary import Boundary
from ..segments import segments_meet

__all__ = ["FrameCheck", "FrameCertificate", "boundary_half_edges"]

# A face's distortion must be below C by this relative margin, so that the same frame recomputed
# another way (an SVD of each face's affine map) cannot come out above C by rounding.
RTOL = 1e-9


def boundary_half_edges(F):
    """Half-edges (b,2) int64 of the triangles ``F`` (m,3) that no other face holds reversed,
    oriented as in their face (the faces lie on their left)."""
    F = np.asarray(F, dtype=np.int64)
    E = F[:, [0, 1, 1, 2, 2, 0]].reshape(-1, 2)
    n = int(F.max()) + 1
    key = E[:, 0] * n + E[:, 1]
    rev = E[:, 1] * n + E[:, 0]
    return E[~np.isin(key, rev)]


@dataclass(frozen=True)
class FrameCheck:
    """What a frame's coordinates prove.

    Attributes
    ----------
    certified : bool, 0 flips, max distortion <= C and no overlap
    distortion : (k,) float64, per face against the rest shape (inf where flipped)
    max_distortion : float
    flipped : int
    overlaps : int, crossing pairs of boundary segments plus loops on the wrong winding side
        (-1 when not tested: the frame already failed on flips or distortion)
    """
    certified: bool
    distortion: np.ndarray
    max_distortion: float
    flipped: int
    overlaps: int


class FrameCertificate:
    """Certifies frames of one island against its rest shape, within a bound C.

    Parameters
    ----------
    rest : (n,2) float64, the rest shape, every face counter-clockwise
    F : (k,3) int64
    bound : float C >= 1

    Attributes
    ----------
    G : (2k, n) csr, rows d/dx then d/dy of each face (against the rest shape)
    area : (k,) float64, rest areas
    edges : (b,2) int64, boundary half-edges
    """

    def __init__(self, rest, F, bound):
        rest = np.asarray(rest, dtype=np.float64)
        F = np.asarray(F, dtype=np.int64)
        self.n, self.k, self.bound = len(rest), len(F), float(bound)
        z = rest[:, 0] + 1j * rest[:, 1]
        self.ops = jacobian_operators(z[F], F, self.n)
        o = self.ops
        nv = self.n
        Gx = sp.csr_array((o.Are + o.Bre)[:, :nv])
        Gy = sp.csr_array((o.Bim - o.Aim)[:, :nv])
        self.G = sp.csr_array(sp.vstack([Gx, Gy]))
        self.area = np.asarray(o.area, dtype=np.float64)
        # Each face is measured from its own first corner (edge vectors), not by G on absolute
        # coordinates: a frame dragged 1e160 away keeps its shape in the differences, which the
        # absolute sums cancel away (a frame measured 4.6 was passed at C = 2).
        self.F = F
        e1, e2 = rest[F[:, 1]] - rest[F[:, 0]], rest[F[:, 2]] - rest[F[:, 0]]
        det = e1[:, 0] * e2[:, 1] - e1[:, 1] * e2[:, 0]
        adj = np.stack([np.stack([e2[:, 1], -e2[:, 0]], -1),
                        np.stack([-e1[:, 1], e1[:, 0]], -1)], -2)
        # the inverse of [e1 e2] by its adjugate: a degenerate rest face gives inf/NaN (its D is
        # then inf, never certified) where np.linalg.inv would raise
        with np.errstate(divide="ignore", invalid="ignore"):
            self._rest_inv = adj / det[:, None, None]
        self.edges = boundary_half_edges(F)
        a, b = self.edges[:, 0], self.edges[:, 1]
        # Fixed topology: the UV point of a boundary vertex is the vertex itself.
        self._bd = Boundary(rest[a], rest[b], np.zeros(len(a), dtype=np.int64),
                            np.zeros(len(a), dtype=np.int64), self.edges, a, b,
                            np.zeros((0, 2), dtype=np.int64))
        self.n_loops, self.loop = _loops(self._bd)

    def distortion(self, U):
        """Per-face conformal distortion (k,) of ``U`` (n,2) against the rest shape, inf where a
        face is flipped or degenerate, and the number of flipped faces."""
        F = self.F
        W = np.stack([U[F[:, 1]] - U[F[:, 0]], U[F[:, 2]] - U[F[:, 0]]], axis=-1)
        J = W @ self._rest_inv          # (k,2,2): rows u, v; columns d/dx, d/dy
        ux, uy, vx, vy = J[:, 0, 0], J[:, 0, 1], J[:, 1, 0], J[:, 1, 1]
        na = 0.5 * np.hypot(ux + vy, vx - uy)
        nb = 0.5 * np.hypot(ux - vy, vx + uy)
        with np.errstate(invalid="ignore", divide="ignore"):
            D = np.where(na > nb, (na + nb) / (na - nb), np.inf)
        return D, int(np.count_nonzero(~(na > nb)))

    def overlaps(self, U, reference=None):
        """Crossings of the boundary of ``U`` (n,2) plus loops on the wrong winding side.

        ``reference`` (n,2): a frame already certified overlap-free; only segments that moved
        from it are tested against the others. Without it every pair is tested."""
        import shapely
        a, b = self.edges[:, 0], self.edges[:, 1]
        p, q = U[a], U[b]
        if reference is None:
            moved = np.arange(len(a))
        else:
            still = np.all(U == reference, axis=1)
            moved = np.flatnonzero(~(still[a] & still[b]))
        if not len(moved):
            return 0
        lo, hi = np.minimum(p, q), np.maximum(p, q)
        pad = 1e-12 * (float(np.max(hi) - np.min(lo)) + 1.0)
        boxes = shapely.box(lo[:, 0] - pad, lo[:, 1] - pad, hi[:, 0] + pad, hi[:, 1] + pad)
        tree = shapely.STRtree(boxes)
        qi, tj = tree.query(boxes[moved])
        i, j = moved[qi].astype(np.int64), tj.astype(np.int64)
        # Each unordered pair once: moved-moved pairs from their smaller index only.
        is_moved = np.zeros(len(a), dtype=bool)
        is_moved[moved] = True
        keep = (i != j) & (~is_moved[j] | (i < j))
        i, j = i[keep], j[keep]
        bd = Boundary(p, q, self._bd.island, self._bd.face, self.edges, a, b, self._bd.interior)
        meets = segments_meet(p, q, i, j)
        pairs = np.stack([i[meets], j[meets]], axis=1)
        crossings = int(crossing_pairs(bd, pairs).sum()) if len(pairs) else 0
        if crossings:
            return crossings
        return int(np.count_nonzero(~_winding_ok(bd, self.loop, self.n_loops)))

    def check(self, U, reference=None):
        """Certify the frame ``U`` (n,2): see the module docstring. Returns ``FrameCheck``."""
        U = np.asarray(U, dtype=np.float64)
        if not np.all(np.isfinite(U)):
            D = np.full(self.k, np.inf)
            return FrameCheck(False, D, np.inf, self.k, -1)
        D, flipped = self.distortion(U)
        mx = float(D.max()) if self.k else 1.0
        if flipped or not mx <= self.bound * (1.0 - RTOL):
            return FrameCheck(False, D, mx, flipped, -1)
        ov = self.overlaps(U, reference)
        return FrameCheck(ov == 0, D, mx, 0, ov)
