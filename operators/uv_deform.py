"""Deform UV islands by their pinned UVs within a conformal bound (Lipman 2012, section 6.1).

The Blender operator ``uv.bd_deform`` gathers the selected faces' UVs and pins and calls
:func:`deform_islands`; this module has no ``bpy`` (numpy, scipy and ``bd_uv`` only), so the
background worker runs it as it is and the tests call it directly.

Per UV island (faces joined by shared UVs, as Blender's UV editor sees them):

- The **rest shape** is the island's current UV layout. Pinned UVs are the handles and their
  current positions the targets; since the artist has just moved them, their *rest* positions are
  taken back from the layout around them: the least-squares conformal fit (LSCM, Lévy et al.
  2002) of their faces to the 3D triangles with every unpinned UV held where it is. A layout that
  only had its pins moved gets its old pins back exactly where it was conformal, e.g. a flat
  mesh's planar projection. Without this the current layout, whose pins already sit on their
  targets, would be its own optimum and nothing would move.
- The deformation (``bd_uv.deform``: BD-ARAP by default, BD-LSCM/ASAP, BD-Dirichlet or
  BD-Biharmonic, eq. 6.1) meets every handle exactly and keeps every face's conformal
  distortion against the rest shape within C with no flip (F_C, eqs. 4.15-4.18, frames reset by
  eq. 4.21).
- An island with fewer than two pinned UV vertices, with every UV but one pinned, or whose rest
  shape has a flipped or zero-area face is refused (left as it is) and the result says why.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp
from scipy.sparse.csgraph import connected_components

from ..bd_uv.deform import deform
from ..bd_uv.energies import energy, jacobian_operators
from ..bd_uv.errors import BDError, CancelledError
from ..bd_uv.frames import _solve_fixed
from ..bd_uv.geometry import local_coordinates

__all__ = ["DeformedIsland", "UVDeformation", "uv_islands", "rest_shape", "deform_islands"]

METHODS = ("arap", "lscm", "dirichlet", "biharmonic")


@dataclass(frozen=True)
class DeformedIsland:
    """One UV island of the selection and what happened to it.

    Attributes
    ----------
    index : int
    faces : (k,) int64, its triangles (rows of the batch's F)
    status : "certified" (deformed, certified by the core) or "refused" (left as it is)
    message : str, why it was refused ("" when certified)
    handles : int, pinned UV vertices
    max_distortion : float, against the rest shape (NaN when refused)
    bad_faces : (j,) int64, triangles of the batch the message refers to (flipped rest faces)
    """

    index: int
    faces: np.ndarray
    status: str
    message: str
    handles: int = 0
    max_distortion: float = float("nan")
    bad_faces: np.ndarray = None


@dataclass(frozen=True)
class UVDeformation:
    """The deformed UVs of a batch of triangles.

    Attributes
    ----------
    corner_uv : (m,3,2) float64, new UV of every corner; NaN on faces of refused islands
    rest_uv : (m,3,2) float64, the rest shape per corner (what distortion is measured against)
    corner_vertex : (m,3) int64, UV vertex of each corner (corners sharing a mesh vertex and a UV)
    face_island : (m,) int64
    islands : list of DeformedIsland
    bound : float, C
    method : str
    """

    corner_uv: np.ndarray
    rest_uv: np.ndarray
    corner_vertex: np.ndarray
    face_island: np.ndarray
    islands: list
    bound: float
    method: str


def uv_islands(F, corner_uv):
    """UV vertices and islands of a triangle batch, as Blender's UV editor joins them.

    Parameters
    ----------
    F : (m,3) int, mesh vertex of each corner
    corner_uv : (m,3,2) float, UV of each corner

    Returns
    -------
    corner_vertex : (m,3) int64, UV vertex of each corner: corners with the same mesh vertex and
        exactly the same UV share one
    uv : (u,2) float64, UV of each UV vertex
    face_island : (m,) int64, connected components of faces through shared UV vertices
    """
    F = np.asarray(F, dtype=np.int64)
    uv = np.asarray(corner_uv, dtype=np.float64).reshape(-1, 2)
    key = np.column_stack([F.reshape(-1).astype(np.float64), uv])
    rows, first, inverse = np.unique(key, axis=0, return_index=True, return_inverse=True)
    corner_vertex = inverse.reshape(-1, 3).astype(np.int64)
    nu = len(rows)
    edges = corner_vertex[:, [0, 1, 1, 2, 2, 0]].reshape(-1, 2)
    graph = sp.coo_array((np.ones(len(edges)), (edges[:, 0], edges[:, 1])), shape=(nu, nu))
    _, label = connected_components(graph, directed=False)
    return corner_vertex, uv[first], label[corner_vertex[:, 0]].astype(np.int64)


def _signed_areas(P, tris):
    a, b, c = P[tris[:, 0]], P[tris[:, 1]], P[tris[:, 2]]
    return 0.5 * ((b[:, 0] - a[:, 0]) * (c[:, 1] - a[:, 1])
                  - (b[:, 1] - a[:, 1]) * (c[:, 0] - a[:, 0]))


def rest_shape(P3, tris, uv, pinned):
    """The rest shape of one island: its UVs, the pinned ones refitted to the layout around them.

    Parameters
    ----------
    P3 : (n,3) float, 3D position of each UV vertex
    tris : (k,3) int, triangles on the UV vertices
    uv : (n,2) float, current UV of each UV vertex
    pinned : (n,) bool, at least two vertices not pinned

    Returns
    -------
    rest : (n,2) float64; unpinned rows are ``uv`` bit for bit, pinned rows minimise the LSCM
        energy ``sum_j A_j |beta_j|^2`` of the map from the 3D triangles (Lipman 2012, eq. 4.6)
        with the unpinned rows held
    """
    n = len(uv)
    ops = jacobian_operators(local_coordinates(P3, tris), tris, n)
    P, _, _ = energy("lscm", ops, np.ones(len(tris), dtype=np.complex128))
    held = np.flatnonzero(~pinned)
    x = _solve_fixed(P, n, held, uv[held, 0] + 1j * uv[held, 1])
    rest = np.array(uv, dtype=np.float64, copy=True)
    rest[pinned, 0], rest[pinned, 1] = x.real[pinned], x.imag[pinned]
    return rest


def deform_islands(V, F, corner_uv, pin_corners, *, method="arap", bound=5.0, frames="current",
                   progress=None, cancel=None):
    """Deform every UV island of a triangle batch by its pinned UVs, within conformal bound C.

    Parameters
    ----------
    V : (n,3) float, mesh positions (only used to put the pinned UVs' rest positions back)
    F : (m,3) int
    corner_uv : (m,3,2) float, current UV of each corner
    pin_corners : (p,) int, flat corner indices (``3 * face + corner``) of pinned UVs
    method : "arap" | "lscm" | "dirichlet" | "biharmonic"
    bound : float C >= 1
    frames : "current" (frames of the current layout, the previous solution; Lipman 2012 eq.
        4.21) or "rest" (frames of the rest shape)
    progress : callable(fraction, message), optional
    cancel : object with ``is_set()``, optional

    Returns
    -------
    UVDeformation

    Raises
    ------
    ValueError for bad options, CancelledError when ``cancel`` is set.
    """
    if method not in METHODS:
        raise ValueError(f"method must be one of {METHODS}, got {method!r}")
    if frames not in ("current", "rest"):
        raise ValueError(f"frames must be 'current' or 'rest', got {frames!r}")
    if not (isinstance(bound, (int, float)) and 1.0 <= bound < np.inf):
        raise ValueError(f"bound must be a finite number >= 1, got {bound!r}")
    V = np.asarray(V, dtype=np.float64)
    F = np.asarray(F, dtype=np.int64)
    m = len(F)
    corner_uv = np.asarray(corner_uv, dtype=np.float64).reshape(m, 3, 2)
    cv, uv, face_island = uv_islands(F, corner_uv)
    vertex_of = np.empty(len(uv), dtype=np.int64)
    vertex_of[cv.reshape(-1)] = F.reshape(-1)
    pinned = np.zeros(len(uv), dtype=bool)
    pinned[cv.reshape(-1)[np.asarray(pin_corners, dtype=np.int64)]] = True
    out = np.full((m, 3, 2), np.nan)
    rest_out = np.full((m, 3, 2), np.nan)
    n_islands = int(face_island.max()) + 1 if m else 0
    order = np.argsort(face_island, kind="stable")
    bounds = np.searchsorted(face_island[order], np.arange(n_islands + 1))
    islands = []
    for i in range(n_islands):
        if cancel is not None and cancel.is_set():
            raise CancelledError("deformation cancelled; nothing was changed")
        if progress is not None:
            progress(i / max(n_islands, 1), f"island {i + 1}/{n_islands}")
        faces = order[bounds[i]:bounds[i + 1]]
        verts, tris = np.unique(cv[faces], return_inverse=True)
        tris = tris.reshape(-1, 3)
        pins = pinned[verts]
        h = int(pins.sum())
        if h < 2:
            islands.append(DeformedIsland(i, faces, "refused", (
                "no pinned UVs" if h == 0 else "only one pinned UV")
                + "; pin at least two UVs (the handles), move them and deform again", h))
            continue
        if h > len(verts) - 2:
            islands.append(DeformedIsland(i, faces, "refused", "every UV but "
                                          f"{len(verts) - h} pinned: nothing is free to follow "
                                          "the pins; unpin some", h))
            continue
        rest = rest_shape(V[vertex_of[verts]], tris, uv[verts], pins)
        rest_out[faces] = rest[tris]
        area = _signed_areas(rest, tris)
        bad = ~(area > 1e-12 * np.abs(area).sum())
        if bad.any():
            islands.append(DeformedIsland(
                i, faces, "refused", f"{int(bad.sum())} flipped or zero-area faces in its "
                "UV layout (with its pinned UVs put back where the layout around them puts "
                "them): the deformation keeps distortion against this layout, so it must be "
                "flip-free; unwrap the island first", h, bad_faces=faces[bad]))
            continue
        handles = np.flatnonzero(pins)
        try:
            res = deform(rest, tris, handles, uv[verts][handles], method=method,
                         bound=float(bound),
                         frames="previous" if frames == "current" else "rest",
                         previous=uv[verts] if frames == "current" else None, cancel=cancel)
        except CancelledError:
            raise
        except (BDError, ValueError) as error:
            islands.append(DeformedIsland(i, faces, "refused", str(error), h))
            continue
        out[faces] = res.uv[tris]
        islands.append(DeformedIsland(i, faces, "certified", "", h, res.max_distortion))
    if progress is not None:
        progress(1.0, "done")
    return UVDeformation(out, rest_out, cv, face_island, islands, float(bound), method)
