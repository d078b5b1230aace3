"""Planar test meshes (Shewchuk's Triangle) and independent checks for planar maps.

Nothing here calls bd_uv: overlaps are found with the separating-axis test on every pair of
triangles, polygons by their own vertices.
"""
import numpy as np
import triangle


def _polygon_pslg(loops):
    V = np.concatenate(loops)
    seg, off = [], 0
    for lp in loops:
        k = np.arange(len(lp))
        seg.append(off + np.stack([k, (k + 1) % len(lp)], 1))
        off += len(lp)
    return V, np.concatenate(seg)


def mesh_polygon(outer, holes=(), hole_points=(), area=0.005, quality=30):
    """Triangle mesh of a polygon with holes: (V (n,2), F (m,3)) counter-clockwise faces."""
    V, seg = _polygon_pslg([np.asarray(outer, float)] + [np.asarray(h, float) for h in holes])
    data = dict(vertices=V, segments=seg)
    if len(hole_points):
        data["holes"] = np.asarray(hole_points, float)
    T = triangle.triangulate(data, f"pq{quality}a{area}")
    return T["vertices"].astype(float), T["triangles"].astype(np.int64)


def circle(n, r=1.0, c=(0.0, 0.0)):
    t = np.linspace(0, 2 * np.pi, n, endpoint=False)
    return np.stack([c[0] + r * np.cos(t), c[1] + r * np.sin(t)], 1)


def square(n_side, half=1.0):
    s = np.linspace(0, 1, n_side, endpoint=False)[:, None]
    c = half * np.array([[-1, -1], [1, -1], [1, 1], [-1, 1]], float)
    return np.concatenate([c[k] + (c[(k + 1) % 4] - c[k]) * s for k in range(4)])


def boundary_edges(F):
    """Edges (e,2) used by exactly one face, oriented as in that face."""
    E = np.concatenate([F[:, [0, 1]], F[:, [1, 2]], F[:, [2, 0]]])
    key = np.sort(E, axis=1)
    _, inv, cnt = np.unique(key, axis=0, return_inverse=True, return_counts=True)
    return E[cnt[inv.ravel()] == 1]


def signed_areas(X, F):
    a, b, c = X[F[:, 0]], X[F[:, 1]], X[F[:, 2]]
    return 0.5 * ((b - a)[:, 0] * (c - a)[:, 1] - (b - a)[:, 1] * (c - a)[:, 0])


def overlapping_pairs(X, F, rtol=1e-9):
    """Number of triangle pairs whose interiors overlap (separating-axis test on all 6 normals)."""
    T = X[F]  # (m,3,2)
    lo, hi = T.min(1), T.max(1)
    scale = np.abs(X).max()
    i, j = np.triu_indices(len(F), 1)
    box = np.all((lo[i] < hi[j]) & (lo[j] < hi[i]), axis=1)
    i, j = i[box], j[box]
    sep = np.zeros(len(i), bool)
    for tri in (T[i], T[j]):
        for k in range(3):
            e = tri[:, (k + 1) % 3] - tri[:, k]
            nrm = np.stack([-e[:, 1], e[:, 0]], 1)
            pa = np.einsum("pkd,pd->pk", T[i], nrm)
            pb = np.einsum("pkd,pd->pk", T[j], nrm)
            tol = rtol * scale * np.linalg.norm(nrm, axis=1)
            sep |= (pa.max(1) <= pb.min(1) + tol) | (pb.max(1) <= pa.min(1) + tol)
    return int((~sep).sum())


def svd_of_maps(X0, X1, F):
    """Singular values (m,2), descending, of each face's affine map X0 -> X1, and its det sign."""
    E0 = np.stack([X0[F[:, 1]] - X0[F[:, 0]], X0[F[:, 2]] - X0[F[:, 0]]], 2)
    E1 = np.stack([X1[F[:, 1]] - X1[F[:, 0]], X1[F[:, 2]] - X1[F[:, 0]]], 2)
    J = E1 @ np.linalg.inv(E0)
    return np.linalg.svd(J, compute_uv=False), np.linalg.det(J)
