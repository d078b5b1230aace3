"""The charts of a finished unwrap measured from their final UVs (stretch, boundary crossings), and
a result with some charts unwrapped again spliced in."""
import copy
import dataclasses

import numpy as np

from ..geometry import face_areas
from ..metrics import face_jacobians
from ..trim import CHUNK
from ..unwrapping.results import UnwrapResult
from .crossings import boundary_crossings
from .topology import charts


def measure_charts(V, F, E, cut, result, chs=None):
    """Per island of a result: max stretch and boundary self-crossings from its final UVs
    (``chs``: ``topology.charts(F, E, cut)`` where the caller has them already)."""
    isl = {int(c.faces[0]): c for c in (charts(F, E, cut) if chs is None else chs)}
    rs = [r for r in result.islands if r.uv is not None and r.status == "certified"]
    st = np.full(len(result.islands), np.nan)
    cr = np.zeros(len(result.islands), dtype=np.int64)
    if not rs:
        return st.tolist(), cr.tolist()
    nvs = np.array([len(r.vertices) for r in rs])
    nfs = np.array([len(r.tris) for r in rs])
    voff = np.concatenate([[0], nvs.cumsum()])
    foff = np.concatenate([[0], nfs.cumsum()])
    fc = np.repeat(np.arange(len(rs)), nfs)
    P = V.take(np.concatenate([r.vertices for r in rs]), axis=0)     # (rows: ``take``, ~4x)
    uv = np.concatenate([r.uv for r in rs])
    tris = np.concatenate([r.tris for r in rs]) + voff[fc][:, None]
    a, b, sa, A3 = (np.empty(len(tris)) for _ in range(4))
    for i in range(0, len(tris), CHUNK):     # per-face numbers, a chunk's temporaries at a time
        t = tris[i:i + CHUNK]
        corner = uv.take(t, axis=0)
        alpha, beta = face_jacobians(P, t, corner)
        a[i:i + CHUNK], b[i:i + CHUNK] = np.abs(alpha), np.abs(beta)
        e1 = corner[:, 1] - corner[:, 0]
        e2 = corner[:, 2] - corner[:, 0]
        sa[i:i + CHUNK] = 0.5 * (e1[:, 0] * e2[:, 1] - e1[:, 1] * e2[:, 0])
        A3[i:i + CHUNK] = face_areas(P, t)
    uv_area = np.bincount(fc, sa, len(rs))
    s = np.sqrt(np.bincount(fc, A3, len(rs)) / np.maximum(uv_area, 1e-300))[fc]
    with np.errstate(divide="ignore", invalid="ignore"):
        fs = np.where(a > b, np.maximum(s * (a + b), 1.0 / (s * (a - b))), np.inf)
    idx = np.array([r.index for r in rs])
    st[idx] = np.maximum.reduceat(fs, foff[:-1])
    z = uv[:, 0] + 1j * uv[:, 1]
    cr[idx] = boundary_crossings(z, [_loop(isl.get(int(r.faces.min())), r) + voff[j]
                                     for j, r in enumerate(rs)])
    return st.tolist(), cr.tolist()


def renumbered(r, j):
    """The island result ``r`` as island ``j``: its index, and a failed one's error (``island``
    and the "island N:" its message starts with) and message along."""
    if r.index == j:
        return r
    if r.error is None:
        return dataclasses.replace(r, index=j)
    err = copy.copy(r.error).renumber(j)
    msg = str(err) if r.message == str(r.error) else r.message
    return dataclasses.replace(r, index=j, error=err, message=msg)


def splice(result, part, sub, voc, m):
    """``result`` with the islands on faces ``sub`` replaced by ``part`` (unwrapped on F[sub])."""
    redo = np.zeros(m, dtype=bool)
    redo[sub] = True
    keep = [r for r in result.islands if not redo[r.faces[0]]]
    new = [dataclasses.replace(r, faces=sub[r.faces], vertices=voc[r.vertices],
                               cut_edges=None if r.cut_edges is None
                               else voc[np.asarray(r.cut_edges, np.int64).reshape(-1, 2)])
           for r in part.islands]
    isl = sorted(keep + new, key=lambda r: int(r.faces.min()))
    isl = [renumbered(r, j) for j, r in enumerate(isl)]
    corner_uv = result.corner_uv.copy()
    corner_uv[sub] = part.corner_uv
    face_island = np.empty(m, dtype=np.int64)
    for r in isl:
        face_island[r.faces] = r.index
    return UnwrapResult(corner_uv, face_island, isl, result.seconds + part.seconds, result.method)


def _loop(chart, r):
    """The boundary loop of ``chart`` in the vertex ids of the unwrap result ``r`` (same chart)."""
    if chart is None or not chart.loops or len(chart.faces) != len(r.faces):
        return np.zeros(0, dtype=np.int64)
    # Same faces, vertices numbered differently: map chart vertex -> result vertex by corner.
    pos = chart.faces.searchsorted(r.faces)
    ids = np.full(len(chart.vertices), -1, dtype=np.int64)
    ids[chart.tris.take(pos, axis=0).ravel()] = r.tris.ravel()
    return ids[chart.loops[0]]
