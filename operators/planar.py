"""Mesh improvement of a flat selection (Lipman 2012, section 6.6), without ``bpy``.

The Blender operator ``mesh.bd_improve`` hands :func:`improve_flat` the selected triangles of each
object; this module checks they lie in one plane, lays them out in that plane's coordinates
(oriented so the faces are counter-clockwise), runs ``bd_uv.improve`` (equilateral frames,
Algorithm 1 with the boundary fixed) and returns new positions for the interior vertices only, on
the plane. Boundary vertices are not returned at all, so the operator leaves them bit for bit.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..bd_uv.errors import CancelledError
from ..bd_uv.improve import equilateral_distortion, improve

__all__ = ["NotFlatError", "FlatPlane", "Improved", "flat_plane", "plane_coordinates",
           "improve_flat", "improve_many", "stored_distortion"]


class NotFlatError(ValueError):
    """The selection is not one flat, consistently oriented sheet of triangles."""


@dataclass(frozen=True)
class FlatPlane:
    """The plane of a flat selection.

    Attributes
    ----------
    origin : (3,) float64
    axes : (2,3) float64, orthonormal in-plane axes, ordered so the faces are counter-clockwise
    off_plane : float, largest distance of a vertex from the plane
    size : float, diagonal of the vertices' bounding box
    """

    origin: np.ndarray
    axes: np.ndarray
    off_plane: float
    size: float


@dataclass(frozen=True)
class Improved:
    """An improved flat selection.

    Attributes
    ----------
    interior : (k,) int64, rows of the input positions that moved (not on the selection's
        boundary)
    positions : (k,3) float64, their new positions, on the plane
    plane : FlatPlane
    result : bd_uv.ImproveResult
    """

    interior: np.ndarray
    positions: np.ndarray
    plane: FlatPlane
    result: object


def flat_plane(P, F, tolerance):
    """The least-squares plane of the vertices of ``F``, if they lie in it.

    Parameters
    ----------
    P : (n,3) float, F : (m,3) int
    tolerance : float, largest distance from the plane allowed, relative to ``size``

    Returns
    -------
    FlatPlane

    Raises
    ------
    NotFlatError when a vertex is further than ``tolerance * size`` from the plane, or the faces
    do not all turn the same way in it (a fold, or inconsistent normals).
    """
    P = np.asarray(P, dtype=np.float64)
    used = np.unique(F)
    origin = P[used].mean(axis=0)
    _, _, Vt = np.linalg.svd(P[used] - origin, full_matrices=False)
    off = float(np.abs((P[used] - origin) @ Vt[2]).max())
    size = float(np.linalg.norm(np.ptp(P[used], axis=0)))
    if not off <= tolerance * size:
        raise NotFlatError(f"the selected faces are not flat: a vertex lies {off:.3g} from their "
                           f"plane (tolerance {tolerance:g} x size {size:.3g}); select flat faces "
                           "only")
    axes = Vt[:2].copy()
    X = (P - origin) @ axes.T
    area = _signed_areas(X, F)
    if (area < 0).sum() > (area > 0).sum():
        axes[1] = -axes[1]
        area = -area
    if not (area > 0).all():
        raise NotFlatError(f"{int((area <= 0).sum())} selected faces are folded over or have zero "
                           "area in the plane; the faces must turn one way (Mesh > Normals > "
                           "Recalculate Outside, or dissolve the degenerate ones)")
    return FlatPlane(origin, axes, off, size)


def _signed_areas(X, F):
    a, b, c = X[F[:, 0]], X[F[:, 1]], X[F[:, 2]]
    return 0.5 * ((b[:, 0] - a[:, 0]) * (c[:, 1] - a[:, 1])
                  - (b[:, 1] - a[:, 1]) * (c[:, 0] - a[:, 0]))


def plane_coordinates(P, plane):
    """(n,2) coordinates of the points (n,3) ``P`` in ``plane``."""
    return (np.asarray(P, dtype=np.float64) - plane.origin) @ plane.axes.T


def improve_flat(P, F, tolerance=1e-5, cancel=None):
    """Make a flat selection's triangles as close to equilateral as bd-uv can certify.

    Parameters
    ----------
    P : (n,3) float, positions; F : (m,3) int, the selected triangles
    tolerance : float, flatness tolerance (see :func:`flat_plane`)
    cancel : object with ``is_set()``, optional

    Returns
    -------
    Improved

    Raises
    ------
    NotFlatError, CancelledError
    """
    F = np.asarray(F, dtype=np.int64)
    plane = flat_plane(P, F, tolerance)
    X = plane_coordinates(P, plane)
    res = improve(X, F, cancel=cancel)
    if cancel is not None and cancel.is_set():
        raise CancelledError("mesh improvement cancelled; nothing was changed")
    moved = np.flatnonzero((res.V2 != X).any(axis=1))
    positions = plane.origin + res.V2[moved] @ plane.axes
    return Improved(moved, positions, plane, res)


def improve_many(problems, tolerance=1e-5, progress=None, cancel=None):
    """:func:`improve_flat` of several objects' selections, one after another.

    Parameters
    ----------
    problems : list of (P, F) pairs
    progress : callable(fraction, message), optional

    Returns
    -------
    list of Improved or NotFlatError (the refusal of that selection), in order
    """
    out = []
    for i, (P, F) in enumerate(problems):
        if progress is not None:
            progress(i / len(problems), f"object {i + 1}/{len(problems)}")
        try:
            out.append(improve_flat(P, F, tolerance, cancel))
        except NotFlatError as error:
            out.append(error)
    return out


def stored_distortion(P, F, plane):
    """Conformal distortion (m,) against the equilateral triangle and signed area (m,) of each
    face of positions ``P`` as stored, in ``plane`` (``bd_uv.equilateral_distortion``)."""
    X = plane_coordinates(P, plane)
    return equilateral_distortion(X, F), _signed_areas(X, F)
