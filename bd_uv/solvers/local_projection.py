"""The local step of the projection iterations: the nearest allowed singular values of a face's
Jacobian, in closed form (Kovalsky, Galun and Lipman 2015, section 4, in 2D without an SVD)."""
import numpy as np

__all__ = ["project_singular_values"]


def project_singular_values(s1, s2, kappa, lo, hi):
    """Nearest point of the convex polygon of allowed signed singular values, per face.

    The polygon is ``{sigma_2 <= sigma_1 <= kappa sigma_2, lo <= sigma_2, sigma_1 <= hi}`` in the
    ``(sigma_1, sigma_2)`` plane (Lipman 2012 eq. 4.9 for the distortion, eqs. 6.3-6.4 for the
    bounds); ``sigma_2 < 0`` encodes a flipped face. For Jacobians with fixed singular vectors the
    Frobenius distance is the Euclidean distance in this plane, so this is the exact projection
    of the Jacobian (Kovalsky et al. 2015, section 4).

    Parameters
    ----------
    s1, s2 : (k,) float, ``s1 >= s2``
    kappa : float or (k,), the distortion bound (> 1)
    lo : (k,) float > 0, lower bound on sigma_2
    hi : (k,) float >= lo, upper bound on sigma_1 (may be inf)

    Returns
    -------
    t1, t2 : (k,) float, the projected singular values
    moved : (k,) bool, faces outside the polygon
    """
    kappa = np.broadcast_to(np.asarray(kappa, dtype=np.float64), s1.shape)
    lo = np.broadcast_to(np.asarray(lo, dtype=np.float64), s1.shape)
    hi = np.broadcast_to(np.asarray(hi, dtype=np.float64), s1.shape)
    inside = (s2 >= lo) & (s1 <= kappa * s2) & (s1 <= hi) & (s1 >= s2)
    t1, t2 = s1.copy(), s2.copy()
    out = np.flatnonzero(~inside)
    if not len(out):
        return t1, t2, ~inside
    x1, x2, kap, lo, hi = s1[out], s2[out], kappa[out], lo[out], hi[out]
    # Above the wedge's apex no projection lands higher than max(s1, kappa lo), so an infinite
    # upper bound can be replaced by that finite one without changing the answer.
    h = np.minimum(hi, np.maximum(np.maximum(x1, kap * lo), lo))
    # Polygon corners, counter-clockwise: apex on the diagonal, end of the bottom edge, the
    # cone's meeting with sigma_1 = h, and the diagonal's.
    ax, ay = lo, lo
    bx, by = np.minimum(kap * lo, h), lo
    cx, cy = h, np.maximum(h / kap, lo)
    dx, dy = h, h
    best = np.full(x1.shape, np.inf)
    y1, y2 = x1.copy(), x2.copy()
    for (px, py, qx, qy) in ((ax, ay, bx, by), (bx, by, cx, cy), (cx, cy, dx, dy),
                             (dx, dy, ax, ay)):
        ex, ey = qx - px, qy - py
        ll = ex * ex + ey * ey
        with np.errstate(invalid="ignore", divide="ignore"):
            t = np.where(ll > 0, ((x1 - px) * ex + (x2 - py) * ey) / ll, 0.0)
        t = np.clip(t, 0.0, 1.0)
        x, y = px + t * ex, py + t * ey
        d = (x - x1) ** 2 + (y - x2) ** 2
        better = d < best
        best = np.where(better, d, best)
        y1 = np.where(better, x, y1)
        y2 = np.where(better, y, y2)
    t1[out], t2[out] = y1, y2
    return t1, t2, ~inside


def nearest_jacobian_parts(t1, t2, na, nb, are, aim, bre, bim):
    """The nearest allowed Jacobian of faces whose singular values moved to ``t1 >= t2``, in its
    conformal / anti-conformal parts, keeping the phases of alpha and beta (a face with alpha = 0
    gets the real alpha ``(t1 + t2) / 2``, likewise beta with ``(t1 - t2) / 2``).

    Parameters
    ----------
    t1, t2 : (k,) float arrays, the projected singular values
    na, nb : (k,) float arrays, |alpha| and |beta| before the projection
    are, aim, bre, bim : (k,) float arrays, real and imaginary parts of alpha and beta

    Returns
    -------
    pre, pim, qre, qim : (k,) float64, real and imaginary parts of the new alpha and beta
    """
    with np.errstate(invalid="ignore", divide="ignore"):
        fa = np.where(na > 0, 0.25 * (t1 + t2) / na, 0.0)
        fb = np.where(nb > 0, 0.25 * (t1 - t2) / nb, 0.0)
    pre = np.where(na > 0, fa * are, 0.5 * (t1 + t2))
    qre = np.where(nb > 0, fb * bre, 0.5 * (t1 - t2))
    return pre, fa * aim, qre, fb * bim
