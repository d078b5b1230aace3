"""The convex bounded-distortion spaces as conic constraints (Lipman 2012, eqs. 4.15-4.18, 4.22).

With ``r_j = Re(w_j alpha_j)`` substituted (a larger r only widens eq. 4.15, so the optimum sets
r_j = Re(w_j alpha_j)), face j's constraints are

    Re(w_j alpha_j) >= sigma                      (4.16, 4.17)
    |beta_j| <= k Re(w_j alpha_j),  k = (C-1)/(C+1)   (4.15, second-order cone), or
    |Re beta_j|, |Im beta_j| <= k Re(w_j alpha_j) / sqrt(2)  (4.22, the L-infinity variant)

and, with stretch bounds ``s <= gamma_j <= Gamma_j <= S`` (section 6.3, ``stretch_space``),

    |alpha_j| <= S - k Re(w_j alpha_j)             (6.3, second-order cone)
    |beta_j| <= Re(w_j alpha_j) - s                (a weaker sufficient form of 6.4, see below)

and continuity (4.18) holds by construction, alpha and beta being linear in the vertex positions.
In Clarabel's form ``A x + s = b, s in K``.
"""
import numpy as np
import scipy.sparse as sp

from .energies import rotated_alpha


def cone_factor(C):
    """k = (C-1)/(C+1) of eq. 4.15 (C a float, or (k,) per face)."""
    C = np.asarray(C, dtype=np.float64) if np.ndim(C) else float(C)
    return (C - 1.0) / (C + 1.0)


def _scaled_rows(k, M):
    """Row j of sparse M times k_j (k a scalar or (rows,))."""
    return k * M if np.ndim(k) == 0 else (sp.diags(k) @ M).tocsr()


def bounded_distortion_space(ops, w, C, sigma, cone="soc"):
    """Constraint blocks of F_C (``cone="soc"``) or F_C^inf (``cone="linf"``) for frames ``w``.

    Parameters
    ----------
    ops : energies.JacobianOperators
    w : (k,) complex unit frames
    C : float >= 1, the distortion bound, or (k,) one per face
    sigma : float > 0, lower bound on Re(w alpha) (eq. 4.17 as r >= sigma)
    cone : "soc" or "linf"

    Returns
    -------
    A : (rows, 2nv) csc, b : (rows,), cones : list of (kind, dim) with kind in {"nonneg", "soc"}
    """
    k = cone_factor(C)
    Ra, _ = rotated_alpha(ops, w)
    nf = Ra.shape[0]
    # Re(w alpha) >= sigma:  -Ra x + s = -sigma, s >= 0
    blocks = [-Ra]
    b = [np.full(nf, -sigma)]
    if cone == "soc":
        # (k Ra x, Bre x, Bim x) in SOC(3), interleaved per face: s = 0 - (-[...] x)
        stack = sp.vstack([_scaled_rows(k, Ra), ops.Bre, ops.Bim]).tocsr()
        perm = np.arange(3 * nf).reshape(3, nf).T.ravel()
        blocks.append(-stack[perm])
        b.append(np.zeros(3 * nf))
        cones = [("nonneg", nf)] + [("soc", 3)] * nf
    elif cone == "linf":
        kR = _scaled_rows(k / np.sqrt(2.0), Ra)
        # kk Ra x -/+ Bre x >= 0 and the same for Bim
        rows = [kR - ops.Bre, kR + ops.Bre, kR - ops.Bim, kR + ops.Bim]
        blocks.extend(-r for r in rows)
        b.append(np.zeros(4 * nf))
        cones = [("nonneg", 5 * nf)]
    else:
        raise ValueError(f"unknown cone {cone!r}: use 'soc' or 'linf'")
    return sp.vstack(blocks).tocsc(), np.concatenate(b), cones


def check_stretch(C, S):
    """Validate a stretch bound ``S`` (meaning 1/S <= gamma <= Gamma <= S) against the bound C.

    Raises
    ------
    ValueError when ``S`` is not a finite number or ``S < sqrt(C)``: the paper's restriction
    ``S / s >= C`` (section 6.3) with ``s = 1/S``; below it F_C with stretch bounds is empty.
    """
    if not (isinstance(S, (int, float)) and 1.0 <= S < np.inf):
        raise ValueError(f"stretch must be a finite number >= 1, got {S!r}")
    if S * S < C * (1.0 - 1e-12):
        raise ValueError(f"stretch {S:g} cannot hold with conformal bound C = {C:g}: singular "
                         f"values in [1/S, S] allow a distortion of at most S^2 = {S * S:g}; use "
                         f"S >= sqrt(C) = {np.sqrt(C):.4g} or lower C")


def stretch_space(ops, w, C, smin, smax, faces=None):
    """Conic rows bounding every face's singular values: ``smin <= gamma_j <= Gamma_j <= smax``.

    Lipman 2012, section 6.3. With ``r_j = Re(w_j alpha_j)`` and ``k = (C-1)/(C+1)``:

    - upper bound, eq. 6.3: ``|alpha_j| <= smax - k r_j``, a 3-dimensional second-order cone
      ``(smax - k r_j, Re alpha_j, Im alpha_j)``. With ``|beta_j| <= k r_j`` (eq. 4.15, or 4.22
      which implies it) it gives ``Gamma_j = |alpha_j| + |beta_j| <= smax``.
    - lower bound: ``|beta_j| <= r_j - smin``, the cone ``(r_j - smin, Re beta_j, Im beta_j)``.
      Since ``|alpha_j| >= r_j`` it gives ``gamma_j = |alpha_j| - |beta_j| >= smin``. The paper's
      eq. 6.4, ``r_j >= (C+1)/2 smin``, implies it (with 4.15), so this space contains the paper's.

    Both use the vertex unknowns only: no auxiliary variable. Append the rows to those of
    ``bounded_distortion_space`` (same unknowns ``x = [Re u; Im u]``).

    Parameters
    ----------
    ops : energies.JacobianOperators
    w : (k,) complex unit frames
    C : float >= 1, the conformal bound the rows are combined with, or (k,) one per face
    smin, smax : float, 0 <= smin <= smax, in the units of the geometry ``ops`` was built on
    faces : (f,) int or bool mask, optional, the faces bounded (default all)

    Returns
    -------
    A : (6f, 2nv) csc, b : (6f,), cones : list of ("soc", 3), 2f entries
    """
    k = cone_factor(C)
    Ra, _ = rotated_alpha(ops, w)
    Are, Aim, Bre, Bim = ops.Are, ops.Aim, ops.Bre, ops.Bim
    if faces is not None:
        Ra, Are, Aim, Bre, Bim = (M[faces] for M in (Ra, Are, Aim, Bre, Bim))
        k = k if np.ndim(k) == 0 else k[faces]
    nf = Ra.shape[0]
    perm = np.arange(3 * nf).reshape(3, nf).T.ravel()
    # (6.3): s = [smax, 0, 0] - [k Ra; -Are; -Aim] x  in SOC(3), interleaved per face
    up = sp.vstack([_scaled_rows(k, Ra), -Are, -Aim]).tocsr()[perm]
    b_up = np.concatenate([np.full(nf, float(smax)), np.zeros(2 * nf)])[perm]
    # lower: s = [-smin, 0, 0] - [-Ra; -Bre; -Bim] x  in SOC(3)
    lo = sp.vstack([-Ra, -Bre, -Bim]).tocsr()[perm]
    b_lo = np.concatenate([np.full(nf, -float(smin)), np.zeros(2 * nf)])[perm]
    return (sp.vstack([up, lo]).tocsc(), np.concatenate([b_up, b_lo]),
            [("soc", 3)] * (2 * nf))


def stretch_conformal_bound(C, smin, smax, room=1.2):
    """The conformal bound to combine with ``stretch_space(smin, smax)`` for a requested C.

    Eq. 6.3 bounds ``Gamma_j`` through ``|alpha_j| + k Re(w_j alpha_j) <= smax``: it charges the
    largest ``|beta_j|`` that C allows (k of eq. 4.15), so with C close to ``R = smax / smin``
    (the paper's restriction ``S / s >= C``, section 6.3) a face is left almost no room for its
    scale (S = 1.015, C = 1.03: a bent grid has no map there). Any smaller C is a subset of F_C,
    so C is lowered to ``max(sqrt(R), R / room)``: R split evenly between the conformal bound and
    the scale when R is small, and at least a factor ``room`` of R left to the scale otherwise.
    The map is still certified at the requested C.

    Returns
    -------
    float, 1 <= result <= C
    """
    R = smax / smin
    return float(max(1.0, min(C, max(np.sqrt(R), R / room))))


def mean_scale_row(ops, w, value=1.0):
    """One equality row fixing the area-weighted mean of ``Re(w_j alpha_j)`` to ``value``.

    Not from the paper: with stretch bounds, energies that reward shrinking (Dirichlet, L1
    stretch) sit at the lower bound, and rescaling the result to UV area = 3D area afterwards
    would push the largest singular values past S. Fixing the mean similarity scale to 1 (the
    island's own scale) keeps that rescaling close to 1. ``Re(w alpha) <= |alpha|``, so the row
    only pins a lower estimate of the scale; certify after rescaling.

    Returns
    -------
    A : (1, 2nv) csc, b : (1,), cones : [("zero", 1)]
    """
    Ra, _ = rotated_alpha(ops, w)
    row = sp.csr_array(ops.area[None, :] @ Ra) / ops.area.sum()
    return row.tocsc(), np.array([float(value)]), [("zero", 1)]


def distortion_epigraph_space(ops, w, k, g, cone="soc"):
    """Constraint blocks of one Dinkelbach step for the smallest max conformal distortion.

    Minimising the max of the ratios ``|beta_j| / Re(w_j alpha_j)`` (eq. 4.15 read as
    ``k_j = (C_j - 1)/(C_j + 1)``) is a generalised fractional program. The normalised Dinkelbach
    step of Crouzeix, Ferland & Schaible (1985, "An algorithm for generalized fractional
    programs", JOTA 47) minimises, with the current map's ratio ``k`` and scales ``g_j``,

        t  subject to  |beta_j| <= k Re(w_j alpha_j) + g_j t,   -k <= t <= 0,

    one always-feasible program (the current map with ``t = 0``); its map's actual max ratio is
    the next ``k``. ``t <= 0`` and the cone give ``Re(w_j alpha_j) >= -g_j t / k >= 0``, so the
    rows of eq. 4.16-4.17 are not needed; a collapsed face fails certification like a flipped one.
    ``cone="linf"`` uses eq. 4.22's rows with the same right-hand side (then the current map is
    feasible at ``t = 0`` when k is its max of ``sqrt(2) max(|Re beta|, |Im beta|) / g``).

    Parameters
    ----------
    ops : energies.JacobianOperators
    w : (m,) complex unit frames
    k : float > 0, the current max ratio (C - 1)/(C + 1)
    g : (m,) float > 0, each face's Re(w_j alpha_j) in the current map
    cone : "soc" or "linf"

    Returns
    -------
    A : (rows, 2nv + 1) csc (the last column is t), b : (rows,), cones : list of (kind, dim)
    """
    Ra, _ = rotated_alpha(ops, w)
    nf, n = Ra.shape
    gcol = sp.csr_array((g, (np.arange(nf), np.zeros(nf, np.int64))), shape=(nf, 1))
    zcol = sp.csr_array((nf, 1))
    # -k <= t <= 0:  s = k + t >= 0 and s = -t >= 0
    t_rows = sp.csr_array(([-1.0, 1.0], ([0, 1], [n, n])), shape=(2, n + 1))
    lhs = sp.hstack([k * Ra, gcol])                  # k Re(w alpha) + g t
    if cone == "soc":
        # (k Re + g t, Re beta, Im beta) in SOC(3), interleaved per face
        stack = sp.vstack([lhs, sp.hstack([ops.Bre, zcol]), sp.hstack([ops.Bim, zcol])]).tocsr()
        perm = np.arange(3 * nf).reshape(3, nf).T.ravel()
        A = sp.vstack([t_rows, -stack[perm]])
        cones = [("nonneg", 2)] + [("soc", 3)] * nf
    elif cone == "linf":
        half = lhs / np.sqrt(2.0)
        Bre, Bim = sp.hstack([ops.Bre, zcol]), sp.hstack([ops.Bim, zcol])
        A = sp.vstack([t_rows] + [-(half + sgn * B) for B in (Bre, Bim) for sgn in (-1.0, 1.0)])
        cones = [("nonneg", 2 + 4 * nf)]
    else:
        raise ValueError(f"unknown cone {cone!r}: use 'soc' or 'linf'")
    b = np.concatenate([[k, 0.0], np.zeros(A.shape[0] - 2)])
    return sp.csc_array(A), b, cones
