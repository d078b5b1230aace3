"""Closed meshes of known genus and independent checks of an automatic-seams result.

Nothing here calls bd_uv: distortion and stretch come from numpy's SVD of each face's 2x2 map,
topology from counting vertices, edges and faces, overlaps from testing every pair of boundary
edges.
"""
import numpy as np

from helpers import reference_jacobians


def torus(R=4.0, r=1.0, nu=48, nv=16):
    """A torus of revolution (genus 1) as a triangulated grid; returns V, F and its two loops.

    Returns
    -------
    V : (nu*nv,3), F : (2*nu*nv,3) outward oriented
    meridian : (nv,) vertex ids of the circle at u = 0 (around the tube)
    inner : (nu,) vertex ids of the inner equator (the shortest loop around the hole)
    """
    u = 2 * np.pi * np.arange(nu) / nu
    v = 2 * np.pi * np.arange(nv) / nv
    U, W = np.meshgrid(u, v, indexing="ij")
    V = np.stack([(R + r * np.cos(W)) * np.cos(U), (R + r * np.cos(W)) * np.sin(U),
                  r * np.sin(W)], axis=-1).reshape(-1, 3)
    idx = np.arange(nu * nv).reshape(nu, nv)
    a = idx
    b = np.roll(idx, -1, axis=0)
    c = np.roll(np.roll(idx, -1, axis=0), -1, axis=1)
    d = np.roll(idx, -1, axis=1)
    F = np.concatenate([np.stack([a, b, c], -1).reshape(-1, 3),
                        np.stack([a, c, d], -1).reshape(-1, 3)])
    return V, F, idx[0, :], idx[:, nv // 2]


def holed_block(holes=4, s=2):
    """A slab with ``holes`` square through-holes in a row (genus = holes), from voxel faces.

    The slab is (2*holes+1) x 3 x 1 cells with the cells (2i+1, 1) removed, each cell split into
    s^3 voxels; every exposed voxel face becomes two triangles, outward oriented.
    """
    nx, ny, nz = (2 * holes + 1) * s, 3 * s, s
    solid = np.ones((nx, ny, nz), dtype=bool)
    for i in range(holes):
        solid[(2 * i + 1) * s:(2 * i + 2) * s, s:2 * s, :] = False
    pad = np.pad(solid, 1)
    quads = []
    eye = np.eye(3, dtype=np.int64)
    for d in range(3):
        eu, ev = eye[(d + 1) % 3], eye[(d + 2) % 3]
        for sign in (1, -1):
            nb = np.roll(pad, -sign, axis=d)
            cells = np.argwhere(pad & ~nb) - 1         # solid voxels with an empty neighbour
            base = cells + (eye[d] if sign > 0 else 0)
            corners = [base, base + eu, base + eu + ev, base + ev]
            if sign < 0:
                corners = corners[::-1]
            quads.append(np.stack(corners, axis=1))
    Q = np.concatenate(quads)                           # (q,4,3) integer corners
    pts, inv = np.unique(Q.reshape(-1, 3), axis=0, return_inverse=True)
    Qi = inv.reshape(-1, 4)
    F = np.concatenate([Qi[:, [0, 1, 2]], Qi[:, [0, 2, 3]]])
    return pts.astype(np.float64) / s, F.astype(np.int64)


def genus(F):
    """Genus of a closed, connected, manifold triangle mesh from its Euler characteristic."""
    E = np.unique(np.sort(np.concatenate([F[:, [0, 1]], F[:, [1, 2]], F[:, [2, 0]]]), axis=1),
                  axis=0)
    chi = len(np.unique(F)) - len(E) + len(F)
    return (2 - chi) // 2


def face_singular_values(V, F, corner_uv):
    """(s1, s2, det) of each face's map from its 3D triangle to its UV triangle (numpy SVD)."""
    J = reference_jacobians(V, F, corner_uv)
    s = np.linalg.svd(J, compute_uv=False)
    return s[:, 0], s[:, 1], np.linalg.det(J)


def chart_topology(tris):
    """(euler characteristic, number of boundary loops) of a chart given in its own vertex ids."""
    a = tris.ravel()
    b = np.roll(tris, -1, axis=1).ravel()
    half = set(zip(a.tolist(), b.tolist()))
    bnd = [(i, j) for i, j in half if (j, i) not in half]
    edges = {tuple(sorted(e)) for e in half}
    chi = len(np.unique(tris)) - len(edges) + len(tris)
    nxt = dict(bnd)
    seen, loops = set(), 0
    for start in nxt:
        if start in seen:
            continue
        loops += 1
        v = start
        while v not in seen:
            seen.add(v)
            v = nxt[v]
    return chi, loops


def boundary_self_crossings(uv, tris, touching=False):
    """Pairs of non-adjacent boundary edges of a chart that intersect in UV (brute force).

    With ``touching``, also pairs that only touch or lie on each other (the two sides of a slit
    mapped onto one segment: the boundary is not injective there either)."""
    a = tris.ravel()
    b = np.roll(tris, -1, axis=1).ravel()
    half = set(zip(a.tolist(), b.tolist()))
    bnd = np.array([(i, j) for i, j in half if (j, i) not in half])
    p, q = uv[bnd[:, 0]], uv[bnd[:, 1]]

    def orient(o, s, t):
        return (s[..., 0] - o[..., 0]) * (t[..., 1] - o[..., 1]) - \
            (s[..., 1] - o[..., 1]) * (t[..., 0] - o[..., 0])
    P1, Q1, P2, Q2 = p[:, None], q[:, None], p[None], q[None]
    d1, d2 = orient(P2, Q2, P1), orient(P2, Q2, Q1)
    d3, d4 = orient(P1, Q1, P2), orient(P1, Q1, Q2)
    cross = (d1 * d2 < 0) & (d3 * d4 < 0)
    if touching:
        lo1, hi1 = np.minimum(P1, Q1), np.maximum(P1, Q1)
        lo2, hi2 = np.minimum(P2, Q2), np.maximum(P2, Q2)
        boxes = np.all((lo1 <= hi2) & (lo2 <= hi1), axis=-1)
        cross = (d1 * d2 <= 0) & (d3 * d4 <= 0) & boxes
    shared = ((bnd[:, None, 0] == bnd[None, :, 0]) | (bnd[:, None, 0] == bnd[None, :, 1]) |
              (bnd[:, None, 1] == bnd[None, :, 0]) | (bnd[:, None, 1] == bnd[None, :, 1]))
    return int(np.triu(cross & ~shared, 1).sum())


def uv_sphere(segments=16, rings=8, flip=()):
    """A closed UV sphere of quads (two triangles each) and two triangle fans at the poles.

    Parameters
    ----------
    flip : iterable of quad ids whose other diagonal is used

    Returns
    -------
    V : (n,3), F : (m,3) outward oriented
    poly : (m,) int64, the polygon (quad or pole triangle) of each triangle
    """
    th = np.pi * np.arange(1, rings) / rings                 # ring latitudes (no poles)
    ph = 2 * np.pi * np.arange(segments) / segments
    T, P = np.meshgrid(th, ph, indexing="ij")
    V = np.concatenate([[[0.0, 0.0, 1.0]],
                        np.stack([np.sin(T) * np.cos(P), np.sin(T) * np.sin(P), np.cos(T)],
                                 -1).reshape(-1, 3),
                        [[0.0, 0.0, -1.0]]])
    ring = 1 + np.arange((rings - 1) * segments).reshape(rings - 1, segments)
    south = len(V) - 1
    j = np.arange(segments)
    tris, poly = [], []
    top = np.stack([np.zeros(segments, np.int64), ring[0, j], ring[0, (j + 1) % segments]], 1)
    tris.append(top)
    poly.append(np.arange(segments))
    a, b = ring[:-1, j], ring[1:, j]
    c, d = ring[1:, (j + 1) % segments], ring[:-1, (j + 1) % segments]
    a, b, c, d = (x.ravel() for x in (a, b, c, d))
    q = np.arange(len(a))
    other = np.isin(q, list(flip))
    t1 = np.where(other[:, None], np.stack([a, b, d], 1), np.stack([a, b, c], 1))
    t2 = np.where(other[:, None], np.stack([b, c, d], 1), np.stack([a, c, d], 1))
    tris += [t1, t2]
    poly += [segments + q, segments + q]
    bot = np.stack([np.full(segments, south), ring[-1, (j + 1) % segments], ring[-1, j]], 1)
    tris.append(bot)
    poly.append(segments + len(a) + np.arange(segments))
    return V, np.concatenate(tris).astype(np.int64), np.concatenate(poly).astype(np.int64)


def sphere_cut():
    """A 32x16 UV sphere cut by the seams ``seams='auto'`` adds at C = S = 1.5: (V, F, the
    edge table, the cut edges (e,) bool)."""
    from bd_uv.seams import unwrap_auto
    from bd_uv.seams.edges import edge_table
    V, F, _ = uv_sphere(32, 16)
    _, added, _ = unwrap_auto(V, F, bound=1.5, stretch=1.5)
    E = edge_table(V, F)
    cut = np.zeros(len(E.ends), dtype=bool)
    k = E.keys(added, len(V))
    cut[k[k >= 0]] = True
    return V, F, E, cut


def record_mapped(monkeypatch, rounds):
    """A list that grows by the vertex count of every chart ``rounds.chart_maps`` maps from
    now on (the seam search's rounds module, patched with ``monkeypatch``)."""
    mapped = []
    real = rounds.chart_maps

    def spy(V, charts, *args, **kwargs):
        mapped.extend(len(c.vertices) for c in charts)
        return real(V, charts, *args, **kwargs)
    monkeypatch.setattr(rounds, "chart_maps", spy)
    return mapped
