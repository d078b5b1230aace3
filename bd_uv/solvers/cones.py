"""Symmetric-cone algebra for the interior-point method: orthant x second-order cones.

Vectors of size m hold every cone's slice (as ``cones`` lists them); per cone dimension d the
second-order slices are gathered coordinate-major as (d, nb) arrays, so every operation is a few
vectorised array expressions over all cones at once (no Python loop over faces). The Jordan
algebra and the Nesterov-Todd scaling follow Vandenberghe 2010, "The CVXOPT linear and quadratic
cone program solvers", sections 2 and 4.
"""
import numpy as np
import scipy.sparse as sp


class Cones:
    """Index arrays of a cone list: the orthant's rows and the second-order cones per dimension.

    Parameters
    ----------
    cones : list of (kind, dim), kind in {"nonneg", "soc"}, in the order of the rows of A

    Attributes
    ----------
    m : int, total rows
    lp : (nlp,) int, the rows of every nonnegative block
    soc : dict {d: (nb, d) int}, the rows of every d-dimensional second-order cone
    degree : int, nlp + number of second-order cones (the barrier parameter nu)
    """

    def __init__(self, cones):
        self.key = list(cones)
        kinds = [k for k, _ in self.key]
        dims = np.fromiter((d for _, d in self.key), np.int64, len(self.key))
        is_lp = np.fromiter((k == "nonneg" for k in kinds), bool, len(kinds))
        is_soc = np.fromiter((k == "soc" for k in kinds), bool, len(kinds))
        bad = ~(is_lp | is_soc)
        if bad.any():
            kind = kinds[int(np.flatnonzero(bad)[0])]
            raise ValueError(f"cone kind {kind!r} is not supported: use 'nonneg' or 'soc'")
        if np.any(dims[is_soc] < 1) or np.any(dims < 0):
            raise ValueError("cone dimensions must be >= 0 (>= 1 for a second-order cone)")
        start = np.concatenate([[0], np.cumsum(dims)])
        self.m = int(start[-1])
        # orthant rows: the ranges of every nonneg block
        lpb = np.flatnonzero(is_lp)
        lens = dims[lpb]
        self.lp = (np.repeat(start[lpb] - np.concatenate([[0], np.cumsum(lens)[:-1]]), lens)
                   + np.arange(int(lens.sum()))) if len(lpb) else np.zeros(0, np.int64)
        # soc[d]: (nb, d) row indices of every d-dimensional cone
        self.soc = {}
        for d in np.unique(dims[is_soc]):
            first = start[np.flatnonzero(is_soc & (dims == d))]
            self.soc[int(d)] = first[:, None] + np.arange(int(d))
        self.degree = len(self.lp) + sum(len(r) for r in self.soc.values())
        # The block-diagonal pattern of W (m x m): the orthant's diagonal, then per cone
        # dimension d the d x d blocks, entries ordered (i, j, cone); ``perm`` maps that order
        # onto CSR order.
        ri, ci = [self.lp], [self.lp]
        for d, rows in self.soc.items():
            for i in range(d):
                for j in range(d):
                    ri.append(rows[:, i])
                    ci.append(rows[:, j])
        ri, ci = np.concatenate(ri), np.concatenate(ci)
        order = np.lexsort((ci, ri))
        self.w_perm = order
        self.w_indices = ci[order].astype(np.int32)
        self.w_indptr = np.concatenate([[0], np.cumsum(np.bincount(ri, minlength=self.m))])

    def block_matrix(self, diag, blocks):
        """CSR matrix from the orthant's diagonal (nlp,) and {d: d x d nested lists of (nb,)}."""
        parts = [diag]
        for d in self.soc:
            parts.extend(blocks[d][i][j] for i in range(d) for j in range(d))
        data = np.concatenate(parts)[self.w_perm]
        return sp.csr_matrix((data, self.w_indices, self.w_indptr), shape=(self.m, self.m))

    def identity(self):
        """e: ones on the orthant, (1, 0, ..., 0) on each second-order cone."""
        e = np.zeros(self.m)
        e[self.lp] = 1.0
        for rows in self.soc.values():
            e[rows[:, 0]] = 1.0
        return e

    def blocks(self, v):
        """{d: (d, nb) view-copies of v on the d-dimensional cones} (coordinate-major)."""
        return {d: v[rows.T] for d, rows in self.soc.items()}

    def margin(self, s):
        """Largest t with s - t e in K (negative when s is outside K)."""
        t = np.inf
        if len(self.lp):
            t = min(t, float(s[self.lp].min()))
        for u in self.blocks(s).values():
            t = min(t, float(np.min(u[0] - _norm1(u))))
        return t

    def step(self, s, ds):
        """Largest alpha >= 0 (up to inf) with s + alpha ds in K, for s in int K."""
        a = np.inf
        if len(self.lp):
            d = ds[self.lp]
            neg = d < 0
            if neg.any():
                a = min(a, float(np.min(-s[self.lp][neg] / d[neg])))
        for rows in self.soc.values():
            u, d = s[rows.T], ds[rows.T]
            # f(alpha) = aa alpha^2 + 2 bb alpha + cc, cc > 0; the first positive root (or none)
            aa = _jdot(d, d)
            bb = _jdot(u, d)
            cc = np.maximum(_jdot(u, u), 0.0)
            disc = bb * bb - aa * cc
            hit = (aa < 0) | ((bb < 0) & (disc >= 0))
            if hit.any():
                den = -bb[hit] + np.sqrt(np.maximum(disc[hit], 0.0))
                with np.errstate(divide="ignore"):
                    a = min(a, float(np.min(np.where(den > 0, cc[hit] / den, 0.0))))
        return a


def _dot1(u, v):
    """sum_{i >= 1} u_i v_i over the leading (cone coordinate) axis."""
    out = u[1] * v[1]
    for i in range(2, len(u)):  # the cone's dimension, not its count
        out = out + u[i] * v[i]
    return out


def _norm1(u):
    return np.sqrt(_dot1(u, u)) if len(u) > 1 else np.zeros_like(u[0])


def _jdot(u, v):
    """u^T J v per cone, u and v (d, nb)."""
    return u[0] * v[0] - (_dot1(u, v) if len(u) > 1 else 0.0)


class NTScaling:
    """Nesterov-Todd scaling W of a pair (s, z) in int K (Vandenberghe 2010, section 4.3).

    Orthant: W = diag(sqrt(s/z)). Second-order cone of dimension d: with a = sqrt(s^T J s),
    b = sqrt(z^T J z), beta = sqrt(a/b), s' = s/a, z' = z/b, gamma = sqrt((1 + s'^T z')/2),
    w = (s' + J z') / (2 gamma):  W = beta [[w0, w1^T], [w1, I + w1 w1^T / (1 + w0)]] and
    W^-1 = (1/beta) [[w0, -w1^T], [-w1, I + w1 w1^T / (1 + w0)]]. Then W z = W^-1 s = lambda.
    W is applied in closed form (O(d) per cone), never as a matrix.
    """

    def __init__(self, cones, s, z):
        self.cones = cones
        self.d_lp = np.sqrt(s[cones.lp] / z[cones.lp])      # (nlp,)
        self.soc = {}
        for d, rows in cones.soc.items():
            us, uz = s[rows.T], z[rows.T]
            a = np.sqrt(np.maximum(_jdot(us, us), 1e-300))
            bq = np.sqrt(np.maximum(_jdot(uz, uz), 1e-300))
            sn, zn = us / a, uz / bq
            gamma = np.sqrt(np.maximum((1.0 + np.sum(sn * zn, axis=0)) / 2.0, 1e-300))
            w = (sn + zn) / (2.0 * gamma)
            w[1:] = (sn[1:] - zn[1:]) / (2.0 * gamma)
            self.soc[d] = (np.sqrt(a / bq), w)
        self._mats = {}

    def _blocks(self, inverse):
        """{d: W's (or W^-1's) d x d blocks as nested lists of (nb,) arrays}."""
        out = {}
        sgn = -1.0 if inverse else 1.0
        for d, (beta, w) in self.soc.items():
            f = 1.0 / beta if inverse else beta
            h = 1.0 / (1.0 + w[0])
            M = [[None] * d for _ in range(d)]
            M[0][0] = f * w[0]
            for i in range(1, d):
                M[0][i] = M[i][0] = sgn * f * w[i]
                for j in range(i, d):
                    M[i][j] = M[j][i] = f * ((i == j) + w[i] * w[j] * h)
            out[d] = M
        return out

    def matrix(self, inverse=False, power=1):
        """W^p or W^-p (p in {1, 2}) as a block-diagonal CSR matrix (cached)."""
        key = (inverse, power)
        if key not in self._mats:
            c = self.cones
            dl = (1.0 / self.d_lp if inverse else self.d_lp) ** power
            B = self._blocks(inverse)
            if power == 2:
                B2 = {}
                for d, M in B.items():
                    B2[d] = [[sum(M[i][k] * M[k][j] for k in range(d)) for j in range(d)]
                             for i in range(d)]
                B = B2
            self._mats[key] = c.block_matrix(dl, B)
        return self._mats[key]

    @staticmethod
    def _soc(par, u, inverse):
        """W u (or W^-1 u) for u (d, nb) or (d, nb, k)."""
        beta, w = par
        if u.ndim == 3:
            w, beta = w[:, :, None], beta[:, None]
        sgn = -1.0 if inverse else 1.0
        wu = _dot1(w, u) if len(u) > 1 else 0.0
        out = np.empty_like(u)
        out[0] = w[0] * u[0] + sgn * wu
        coef = sgn * u[0] + wu / (1.0 + w[0])
        out[1:] = u[1:] + coef * w[1:]
        return out / beta if inverse else out * beta

    def apply(self, v, inverse=False, power=1):
        """W^p v or W^-p v, p in {1, 2}, for v of size m."""
        return self.matrix(inverse, power) @ v

    def inv_blocks(self, d, G):
        """W^-1 G for the d-dimensional cones' blocks G (d, nb, k)."""
        return self._soc(self.soc[d], G, True)


def jordan_product(cones, u, v):
    """Jordan product u o v (orthant: elementwise; SOC: (u^T v, u0 v1 + v0 u1))."""
    out = np.empty_like(u)
    out[cones.lp] = u[cones.lp] * v[cones.lp]
    for rows in cones.soc.values():
        a, b = u[rows.T], v[rows.T]
        r = np.empty_like(a)
        r[0] = np.sum(a * b, axis=0)
        r[1:] = a[0] * b[1:] + b[0] * a[1:]
        out[rows.T] = r
    return out


def jordan_divide(cones, lam, r):
    """u with lam o u = r (lam in int K)."""
    out = np.empty_like(r)
    out[cones.lp] = r[cones.lp] / lam[cones.lp]
    for rows in cones.soc.values():
        lm, rr = lam[rows.T], r[rows.T]
        u = np.empty_like(rr)
        u[0] = (lm[0] * rr[0] - (_dot1(lm, rr) if len(lm) > 1 else 0.0)) / _jdot(lm, lm)
        u[1:] = (rr[1:] - u[0] * lm[1:]) / lm[0]
        out[rows.T] = u
    return out


def lift(cones, s, delta):
    """s + max(0, delta - margin_i) e_i on every cone i (margin: s_i, or s_0 - |s_1| on a SOC)."""
    out = s.copy()
    lp = cones.lp
    out[lp] = np.maximum(s[lp], delta)
    for rows in cones.soc.values():
        u = s[rows.T]
        out[rows[:, 0]] += np.maximum(delta - (u[0] - _norm1(u)), 0.0)
    return out


def jordan_inverse(cones, s):
    """s^-1 (s o s^-1 = e): 1/s on the orthant, J s / (s^T J s) on each second-order cone."""
    out = np.empty_like(s)
    out[cones.lp] = 1.0 / s[cones.lp]
    for rows in cones.soc.values():
        u = s[rows.T]
        v = u / _jdot(u, u)
        v[1:] *= -1.0
        out[rows.T] = v
    return out
