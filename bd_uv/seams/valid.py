"""Whether no island of a mesh can fail ``mesh.islands``' validation, whatever the seams: checked
on the whole mesh at once, so the seam search (``auto.unwrap_auto``) can skip ``islands``."""
import numpy as np

from ..mesh import DEGENERATE_RATIO, measurable
from .cut_vertices import cut_mesh
from ..trim import CHUNK


def valid_everywhere(V, F, E, A):
    """Whether no island can fail ``mesh.islands``' validation (whatever the seams), checked
    on the whole mesh at once, so the search can skip ``islands`` (a few per cent of its time).

    Conservative: every coordinate finite, no face of zero area by ``mesh.islands``' test, no
    edge of three or more faces, every interior edge's two faces oriented alike, no two faces on
    the same three vertices, every vertex a single fan of corners. Where any fails (even a
    vertex fan ``mesh.islands`` would accept, joining two islands), ``islands`` decides.

    Parameters
    ----------
    V : (n,3) float64, F : (m,3) int64, E : edges.EdgeTable, A : (m,) float64 face areas

    Returns
    -------
    bool
    """
    # Per-face tests ``CHUNK`` faces at a time: the (m,3,3) corner positions and their
    # differences were ~110 MB at once on a 500k-face mesh, the set-up's peak.
    for i in range(0, len(F), CHUNK):
        P = V.take(F[i:i + CHUNK], axis=0)          # (rows: ``take``, ~4x cheaper)
        if not measurable(P).all():   # NaN, inf, or beyond float64's fourth powers
            return False
        lmax2 = np.max(np.sum((P - np.roll(P, -1, axis=1)) ** 2, axis=2), axis=1)
        with np.errstate(invalid="ignore"):
            if not np.all(2 * A[i:i + CHUNK] > DEGENERATE_RATIO * lmax2):
                return False
        # Two faces on the same vertices share all three edges: each edge leads to the other.
        ef = E.faces.take(E.face_edges[i:i + CHUNK], axis=0)    # (k,3,2)
        me = np.arange(i, i + len(ef))[:, None]
        other = np.where(ef[:, :, 0] == me, ef[:, :, 1], ef[:, :, 0])
        if np.any((other[:, 0] >= 0) & (other[:, 0] == other[:, 1])
                  & (other[:, 1] == other[:, 2])):
            return False
    P = lmax2 = ef = me = other = None
    if (np.bincount(E.face_edges.ravel(), minlength=len(E.ends)) > 2).any():
        return False
    c = E.corners[E.faces[:, 1] >= 0]
    nxt = lambda h: h - h % 3 + (h % 3 + 1) % 3
    if np.any((nxt(c[:, 0, 0]) == c[:, 0, 1]) == (nxt(c[:, 1, 0]) == c[:, 1, 1])):
        return False
    del c
    # One cut vertex per vertex with no seam: where the fans are known, the cut vertices of no
    # seam are the fans themselves (a fan's one run of corners), counted without cutting.
    if E.fans is not None:
        fans = len(E.fans.starts) - 1
    else:
        fans = len(cut_mesh(F, E, np.zeros(len(E.ends), dtype=bool))[1])
    return fans == np.count_nonzero(np.bincount(np.asarray(F).ravel()))
