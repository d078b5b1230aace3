"""Distortion metrics that certify a result from its final UVs alone (Lipman 2012, eqs. 4.6-4.9)."""
import numpy as np

from .array_calls import einsum, quiet
from .geometry import face_areas, gradient_operators, local_coordinates


def face_jacobians(V, F, corner_uv, G=None):
    """Similarity and anti-similarity parts of each face's affine map (eq. 4.6).

    Parameters
    ----------
    V : (n,3) float array
    F : (m,3) int array
    corner_uv : (m,3,2) float array, UV of each face corner
    G : (m,2,3) float64, optional, ``gradient_operators(local_coordinates(V, F))`` when known
        (``one_disk.Disk.G``: the same bits)

    Returns
    -------
    alpha, beta : (m,) complex128
        The map is ``z -> alpha z + beta conj(z) + delta`` in each face's canonical local frame.
    """
    if G is None:
        G = gradient_operators(local_coordinates(V, F))
    uv = np.asarray(corner_uv, dtype=np.float64)
    # from the face's first corner: the gradient of a constant is zero, and coordinates far from
    # the origin for the face's size (a piece 5e-14 across at u = 0.98) would cancel in the sum,
    # off by 5e-4 in D; the differences of nearby floats are exact
    uv = uv - uv[:, :1]
    # (``array_calls.einsum``: np.einsum's own compiled call, without its wrapper)
    gx = einsum("mkc,mc->mk", G, uv[:, :, 0])  # (du/dx, du/dy)
    gy = einsum("mkc,mc->mk", G, uv[:, :, 1])  # (dv/dx, dv/dy)
    alpha = 0.5 * ((gx[:, 0] + gy[:, 1]) + 1j * (gy[:, 0] - gx[:, 1]))
    beta = 0.5 * ((gx[:, 0] - gy[:, 1]) + 1j * (gy[:, 0] + gx[:, 1]))
    return alpha, beta


def signed_uv_areas(corner_uv):
    """Signed area of each UV triangle (positive when counter-clockwise).

    Parameters
    ----------
    corner_uv : (m,3,2) float array

    Returns
    -------
    (m,) float64
    """
    uv = np.asarray(corner_uv, dtype=np.float64)
    e1 = uv[:, 1] - uv[:, 0]
    e2 = uv[:, 2] - uv[:, 0]
    return 0.5 * (e1[:, 0] * e2[:, 1] - e1[:, 1] * e2[:, 0])


def flipped_faces(V, F, corner_uv):
    """Faces whose UV triangle is flipped or collapsed (signed UV area <= 0, or non-finite).

    Returns
    -------
    (m,) bool
    """
    A = signed_uv_areas(corner_uv)
    return ~(A > 0)


def conformal_distortion(V, F, corner_uv, G=None):
    """Conformal distortion ``D = (|alpha|+|beta|) / (|alpha|-|beta|)`` of each face (eq. 4.9)
    (G: ``face_jacobians``').

    Returns
    -------
    D : (m,) float64
        ``inf`` for flipped, collapsed or degenerate faces.
    """
    alpha, beta = face_jacobians(V, F, corner_uv, G)
    return _distortion(np.abs(alpha), np.abs(beta), flipped_faces(V, F, corner_uv))


def _distortion(a, b, flipped):
    """``conformal_distortion`` from |alpha|, |beta| and the flipped faces."""
    with quiet("invalid", "divide"):
        D = (a + b) / (a - b)
    bad = ~(a > b) | ~np.isfinite(D) | flipped
    D[bad] = np.inf
    return D


def singular_values(V, F, corner_uv, normalize=True):
    """Singular values of each face's map, ``Gamma = |alpha|+|beta|``, ``gamma = |alpha|-|beta|``.

    Lipman 2012, eqs. 4.7-4.8; for certifying the stretch bounds of section 6.3.

    Parameters
    ----------
    V : (n,3) float array
    F : (m,3) int array, the faces of one island (the scale is the island's as a whole)
    corner_uv : (m,3,2) float array
    normalize : bool, measure relative to the island's own scale: the UVs scaled so the total UV
        area equals the total 3D area (as written UVs are). False: relative to the 3D geometry.

    Returns
    -------
    smax, smin : (m,) float64
        ``smin`` is negative for a flipped face (``|beta| > |alpha|``); NaN for degenerate faces.
    """
    alpha, beta = face_jacobians(V, F, corner_uv)
    return _singular(V, F, signed_uv_areas(corner_uv), np.abs(alpha), np.abs(beta), normalize)


def _singular(V, F, signed_area, a, b, normalize, A=None):
    """``singular_values`` from the signed UV areas, |alpha| and |beta| (A: ``face_areas(V,
    F)`` when known)."""
    smax, smin = a + b, a - b
    if normalize:
        uv_area = np.sum(np.abs(signed_area))
        A = face_areas(V, F) if A is None else A
        scale = np.sqrt(np.sum(A) / uv_area) if uv_area > 0 else np.nan
        smax, smin = smax * scale, smin * scale
    return smax, smin


def certify_measured(V, F, corner_uv, bound, normalize=True, rtol=1e-6, faces=None):
    """``certify`` and ``singular_values`` of one map from one evaluation of its Jacobians (the
    same numbers as the two calls). ``faces``: (G, A), the faces' gradient operators and areas
    in V (``face_jacobians``' G, ``face_areas``) when known: the same bits.

    Returns
    -------
    ok, D, n_flipped : as ``certify``
    smax, smin : as ``singular_values``
    """
    G, A = (None, None) if faces is None else faces
    alpha, beta = face_jacobians(V, F, corner_uv, G)
    a, b = np.abs(alpha), np.abs(beta)
    signed = signed_uv_areas(corner_uv)
    flipped = ~(signed > 0)
    D = _distortion(a, b, flipped)
    n_flipped = int(flipped.sum())
    ok = n_flipped == 0 and bool(np.all(D <= bound * (1.0 + rtol)))
    return (ok, D, n_flipped) + _singular(V, F, signed, a, b, normalize, A)


def certify(V, F, corner_uv, bound, rtol=1e-6):
    """Check a map: no flipped face and every face's distortion within ``bound``.

    Returns
    -------
    ok : bool
    D : (m,) float64 distortion per face
    n_flipped : int
    """
    D = conformal_distortion(V, F, corner_uv)
    n_flipped = int(flipped_faces(V, F, corner_uv).sum())
    ok = n_flipped == 0 and bool(np.all(D <= bound * (1.0 + rtol)))
    return ok, D, n_flipped


def mean_distortion(V, F, D, A=None):
    """Area-weighted mean of the finite distortions (A: ``face_areas(V, F)`` when known)."""
    A = face_areas(V, F) if A is None else A
    finite = np.isfinite(D)
    if not finite.any():
        return float("inf")
    return float(np.sum(A[finite] * D[finite]) / np.sum(A[finite]))
