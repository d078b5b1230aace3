"""Test shapes for the overlap checks, and an independent triangle-triangle overlap test.

Nothing here calls ``bd_uv``: the overlap test separates two UV triangles by the six edge normals
(separating axis theorem), so a layout the product calls overlap-free is re-checked by code that
shares no line with it.
"""
import numpy as np


def strip(n, length=1.0, width=0.1):
    """A flat strip of ``n`` quads (2n triangles) in the xy-plane, counter-clockwise.

    Returns
    -------
    V : (2n+2,3), F : (2n,3), s : (2n+2,) arc length, t : (2n+2,) across (0 or width)
    """
    s = np.repeat(np.linspace(0.0, length, n + 1), 2)
    t = np.tile([0.0, width], n + 1)
    V = np.stack([s, t, np.zeros_like(s)], axis=1)
    i = 2 * np.arange(n)
    F = np.concatenate([np.stack([i, i + 2, i + 3], 1), np.stack([i, i + 3, i + 1], 1)])
    return V, F, s, t


def strip_along(curve, normal, n=200, width=0.1, length=1.0):
    """UVs that lay a strip of ``n`` quads along a plane curve: corner (s, t) goes to
    ``curve(s) + t * normal(s)``. Returns V, F (the flat strip) and corner_uv (2n,3,2)."""
    V, F, s, t = strip(n, length, width)
    P = curve(s) + t[:, None] * normal(s)
    return V, F, P[F]


def spiral_uv(turns, n=300, width=0.3, r0=1.0, pitch=0.25):
    """An Archimedean spiral strip: inner edge r = r0 + pitch * theta / (2 pi)."""
    L = 2 * np.pi * turns

    def curve(s):
        th = s / 1.0 * L
        r = r0 + pitch * th / (2 * np.pi)
        return np.stack([r * np.cos(th), r * np.sin(th)], 1)

    def normal(s):  # towards the centre: the strip stays counter-clockwise
        th = s * L
        return -np.stack([np.cos(th), np.sin(th)], 1)
    return strip_along(curve, normal, n, width, 1.0)


def spiral_strip(turns=2.5, n=300, width=0.3, pitch=0.25, rise=0.05):
    """An Archimedean spiral strip in 3D, wider than its pitch and rising ``rise`` per turn so it
    does not cut itself: flattened, its turns lie across each other. Returns V, F."""
    V, F, uv = spiral_uv(turns, n, width, pitch=pitch)
    P = np.zeros((len(V), 2))
    P[F.ravel()] = uv.reshape(-1, 2)
    th = np.repeat(np.linspace(0, 2 * np.pi * turns, n + 1), 2)
    return np.concatenate([P, rise * th[:, None] / (2 * np.pi)], 1), F


def figure8_uv(n=400, width=0.05):
    """A strip along a lemniscate (x, y) = (sin 2u, sin u) / 2 for u in (-1.2, 4.3): it passes
    the middle twice, so its boundary crosses itself there."""
    u0, u1 = -1.2, 4.3

    def pos(s):
        u = u0 + s * (u1 - u0)
        return np.stack([np.sin(2 * u), np.sin(u)], 1) * 0.5

    def normal(s):
        u = u0 + s * (u1 - u0)
        d = np.stack([2 * np.cos(2 * u), np.cos(u)], 1)
        d /= np.linalg.norm(d, axis=1, keepdims=True)
        return np.stack([-d[:, 1], d[:, 0]], 1)
    return strip_along(pos, normal, n, width, 1.0)


def helicoid_ribbon(turns=2.2, n_around=110, n_across=2, r0=0.3, r1=1.0, pitch=0.35):
    """A helicoid ribbon: (r cos th, r sin th, pitch * th), r in [r0, r1]. Returns V, F."""
    th = np.linspace(0, 2 * np.pi * turns, n_around + 1)
    r = np.linspace(r0, r1, n_across + 1)
    T, R = np.meshgrid(th, r, indexing="ij")
    V = np.stack([R * np.cos(T), R * np.sin(T), pitch * T], -1).reshape(-1, 3)
    a = (np.arange(n_around)[:, None] * (n_across + 1) + np.arange(n_across)[None, :]).ravel()
    b, c, d = a + n_across + 1, a + n_across + 2, a + 1
    F = np.concatenate([np.stack([a, b, c], 1), np.stack([a, c, d], 1)])
    return V, F


def folded_strip(turns=1.3, n=240, r0=1.0, width=0.3, rise=0.02):
    """A flat strip bent round in its own plane until it lies across itself, kept apart in 3D by
    a small rise (``rise`` per turn): nearly flat, so its UV map lays the strip over itself.
    Returns V, F."""
    th = np.linspace(0, 2 * np.pi * turns, n + 1)
    r = np.array([r0, r0 + width])
    T, R = np.meshgrid(th, r, indexing="ij")
    V = np.stack([R * np.cos(T), R * np.sin(T), rise * T / (2 * np.pi)], -1).reshape(-1, 3)
    a = 2 * np.arange(n)
    F = np.concatenate([np.stack([a, a + 2, a + 3], 1), np.stack([a, a + 3, a + 1], 1)])
    return V, F


def overlapping_triangle_pairs(uv, rel_tol=1e-9):
    """Pairs of UV triangles whose interiors overlap (separating axis test on the 6 edge normals).

    Parameters
    ----------
    uv : (m,3,2) float array

    Returns
    -------
    (k,2) int64 pairs (i < j)
    """
    uv = np.asarray(uv, dtype=np.float64)
    m = len(uv)
    scale = float(np.ptp(uv.reshape(-1, 2), axis=0).max()) or 1.0
    eps = rel_tol * scale
    lo, hi = uv.min(axis=1), uv.max(axis=1)
    out = []
    for start in range(0, m, 256):            # blocks of rows keep memory bounded
        i = np.arange(start, min(m, start + 256))
        I, J = np.meshgrid(i, np.arange(m), indexing="ij")
        keep = (J > I) & np.all(lo[I] < hi[J] - eps, -1) & np.all(lo[J] < hi[I] - eps, -1)
        I, J = I[keep], J[keep]
        # each pair measured from a corner of its first triangle: projecting coordinates far from
        # the origin (an island 1e-8 across at u = 0.98) onto its short edge normals rounded
        # more than eps, and two triangles sharing an edge were taken to overlap
        A, B = uv[I] - uv[I][:, :1], uv[J] - uv[I][:, :1]
        separated = np.zeros(len(I), dtype=bool)
        for T in (A, B):
            for e in range(3):
                d = T[:, (e + 1) % 3] - T[:, e]
                nrm = np.stack([-d[:, 1], d[:, 0]], 1)
                pa = np.einsum("kcj,kj->kc", A, nrm)
                pb = np.einsum("kcj,kj->kc", B, nrm)
                ln = np.linalg.norm(nrm, axis=1)
                separated |= (pa.max(1) <= pb.min(1) + eps * ln) \
                    | (pb.max(1) <= pa.min(1) + eps * ln)
        out.append(np.stack([I[~separated], J[~separated]], 1))
    return np.concatenate(out) if out else np.zeros((0, 2), np.int64)
