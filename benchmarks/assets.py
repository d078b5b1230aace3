"""Benchmark meshes made from the shared meshes or from a seed, written as OBJ files.

Every asset is a file, so Blender and bd-uv read the same triangles in the same order, and the
same call with the same inputs writes the same file (a re-run reuses it):

- ``subdivided(path, times)``: ``trimesh.remesh.subdivide`` (each triangle into four) ``times``
  times: face.obj 51,712 -> 206,848 -> 827,392 faces; mannequin-devil 25,888 -> 103,552 -> 414,208.
- ``patch(path, faces)``: the smallest ball of whole face rings (breadth-first over shared edges)
  around the face nearest the vertex centroid holding at least ``faces`` faces: smaller meshes of
  the same surface.
- ``many_islands(n, seed)``: ``n`` separate small bumpy grid patches (8 faces each for most, up to
  288), about half of those with at least 4x4 cells with a hole; each a separate connected
  component, so Blender's unwrap and ``bd_uv.islands`` both see ``n`` islands without seams.
"""
from __future__ import annotations

import os
import tempfile

import numpy as np

DEFAULT_DIR = os.path.join(tempfile.gettempdir(), "bd_uv_bench_assets")


def write_obj(path: str, V: np.ndarray, F: np.ndarray) -> str:
    """Write ``V`` (n,3) and ``F`` (m,3) 0-based as a plain OBJ (``v`` and ``f`` lines only)."""
    os.makedirs(os.path.dirname(os.path.abspath(path)), exist_ok=True)
    tmp = path + ".part"
    with open(tmp, "w", encoding="ascii") as fh:
        np.savetxt(fh, np.asarray(V, dtype=np.float64), fmt="v %.17g %.17g %.17g")
        np.savetxt(fh, np.asarray(F, dtype=np.int64) + 1, fmt="f %d %d %d")
    os.replace(tmp, path)
    return path


def read_obj_fast(path: str) -> tuple[np.ndarray, np.ndarray]:
    """Read an OBJ written by ``write_obj`` (``v x y z`` and ``f a b c`` lines only)."""
    with open(path, "rb") as fh:
        lines = fh.read().split(b"\n")
    v = [ln[2:] for ln in lines if ln.startswith(b"v ")]
    f = [ln[2:] for ln in lines if ln.startswith(b"f ")]
    V = np.array(b" ".join(v).split(), dtype=np.float64).reshape(-1, 3)
    F = np.array(b" ".join(f).split(), dtype=np.int64).reshape(-1, 3) - 1
    return V, F


def _stem(path):
    return os.path.splitext(os.path.basename(path))[0]


def subdivided(path: str, times: int, out_dir: str = DEFAULT_DIR) -> str:
    """``path`` subdivided ``times`` times with ``trimesh.remesh.subdivide``; the OBJ's path."""
    out = os.path.join(out_dir, f"{_stem(path)}-sub{times}.obj")
    if os.path.exists(out):
        return out
    import trimesh.remesh

    from measure import load_mesh_by_index

    V, F = load_mesh_by_index(path)
    for _ in range(times):
        V, F = trimesh.remesh.subdivide(V, F)
    return write_obj(out, V, F)


def _face_adjacency(F):
    """Pairs of faces sharing an edge: (p,2) int64 (each interior edge once)."""
    m = len(F)
    e = np.sort(F[:, [0, 1, 1, 2, 2, 0]].reshape(-1, 2), axis=1)
    fid = np.repeat(np.arange(m), 3)
    key = e[:, 0] * (F.max() + 1) + e[:, 1]
    order = np.argsort(key, kind="stable")
    k, f = key[order], fid[order]
    same = k[1:] == k[:-1]
    return np.c_[f[:-1][same], f[1:][same]]


def is_disk(F: np.ndarray) -> bool:
    """Whether the faces ``F`` (of a manifold mesh) form one topological disk: one connected
    piece, every vertex on the boundary on exactly two boundary edges (no two rings meeting at a
    vertex only: a bowtie), and Euler characteristic V - E + F = 1."""
    from scipy.sparse import coo_array
    from scipy.sparse.csgraph import connected_components

    F = np.asarray(F, dtype=np.int64)
    if not len(F):
        return False
    e = np.sort(F[:, [0, 1, 1, 2, 2, 0]].reshape(-1, 2), axis=1)
    edges, count = np.unique(e, axis=0, return_counts=True)
    if (count > 2).any():
        return False
    used = np.unique(F)
    n = int(used.max()) + 1
    on_boundary = np.bincount(edges[count == 1].ravel(), minlength=n)[used]
    if not np.isin(on_boundary, (0, 2)).all():
        return False
    pieces = connected_components(coo_array((np.ones(len(edges)), (edges[:, 0], edges[:, 1])),
                                            shape=(n, n)), directed=False)[1][used]
    return len(np.unique(pieces)) == 1 and len(used) - len(edges) + len(F) == 1


def patch(path: str, faces: int, out_dir: str = DEFAULT_DIR) -> str:
    """Whole breadth-first face rings around the most central face, until >= ``faces`` faces.

    The centre is the face whose centroid is nearest the mean of the vertices; rings grow over
    shared edges (``scipy.sparse.csgraph.breadth_first_order``), and only whole rings are kept.
    Rings are added until the kept faces form a disk (:func:`is_disk`: growing rings can meet at
    a vertex only, and a bowtie is no disk; ValueError if none does). Unreferenced vertices are
    dropped, the face order is the file's.
    """
    out = os.path.join(out_dir, f"{_stem(path)}-patch{faces}.obj")
    if os.path.exists(out):
        return out
    import scipy.sparse as sp
    from scipy.sparse.csgraph import shortest_path

    from measure import load_mesh_by_index

    V, F = load_mesh_by_index(path)
    adj = _face_adjacency(F)
    m = len(F)
    A = sp.coo_array((np.ones(2 * len(adj)), (np.r_[adj[:, 0], adj[:, 1]],
                                               np.r_[adj[:, 1], adj[:, 0]])), shape=(m, m)).tocsr()
    cen = V[F].mean(axis=1)
    seed = int(np.argmin(np.linalg.norm(cen - V.mean(axis=0), axis=1)))
    ring = shortest_path(A, unweighted=True, indices=seed)
    ring = np.where(np.isfinite(ring), ring, np.inf)
    levels = np.sort(ring[np.isfinite(ring)])
    r = levels[min(faces, len(levels)) - 1]
    keep = np.flatnonzero(ring <= r)
    for nxt in np.unique(levels[levels > r]):
        if is_disk(F[keep]):
            break
        keep = np.flatnonzero(ring <= nxt)
    if not is_disk(F[keep]):
        raise ValueError(f"{path}: no whole ring around its central face closes into a disk")
    sub = F[keep]
    used, inv = np.unique(sub, return_inverse=True)
    return write_obj(out, V[used], inv.reshape(-1, 3))


def _grid(n, m):
    """Triangles of an n x m vertex grid (vertex id i * m + j), two per cell, counter-clockwise
    in (i, j); and each triangle's cell (i, j)."""
    i, j = np.meshgrid(np.arange(n - 1), np.arange(m - 1), indexing="ij")
    i, j = i.ravel(), j.ravel()
    a, b, c, d = i * m + j, (i + 1) * m + j, i * m + j + 1, (i + 1) * m + j + 1
    F = np.r_[np.c_[a, b, d], np.c_[a, d, c]]
    return F, np.r_[i, i], np.r_[j, j]


def many_islands(n: int = 1000, seed: int = 0, out_dir: str = DEFAULT_DIR) -> str:
    """``n`` separate bumpy grid patches as one OBJ (deterministic in ``seed``); the OBJ's path.

    Each patch: an a x b vertex grid (85%: 3 x 3 = 8 faces; 12%: 4-5 per side, 18-32 faces;
    3%: 7-13 per side, 72-288 faces) over a unit square, lifted to a height field
    ``h sin(fx x + px) cos(fy y + py)`` (h 0.05-0.3, f 2-6) with in-plane jitter of 10% of a cell,
    and, for grids of at least 5 x 5 vertices with probability 1/2, a hole: the central block of
    max(1, (side-1)//4)^2 cells removed (unreferenced vertices dropped). Then a random rotation and
    a place on a 10 x 10 x 10 lattice of spacing 2, so no two patches touch.
    """
    out = os.path.join(out_dir, f"islands{n}-seed{seed}.obj")
    if os.path.exists(out):
        return out
    rng = np.random.default_rng(seed)
    Vs, Fs, off = [], [], 0
    side = int(np.ceil(n ** (1 / 3)))
    for k in range(n):
        r = rng.random()
        if r < 0.85:
            a = b = 3
        elif r < 0.97:
            a, b = rng.integers(4, 6, size=2)
        else:
            a, b = rng.integers(7, 14, size=2)
        F, ci, cj = _grid(a, b)
        if a >= 5 and b >= 5 and rng.random() < 0.5:
            h = max(1, (min(a, b) - 1) // 4)
            i0, j0 = (a - 1 - h) // 2, (b - 1 - h) // 2
            F = F[~((ci >= i0) & (ci < i0 + h) & (cj >= j0) & (cj < j0 + h))]
        x, y = np.meshgrid(np.linspace(0, 1, a), np.linspace(0, 1, b), indexing="ij")
        x, y = x.ravel(), y.ravel()
        cell = 1.0 / max(a - 1, b - 1)
        x = x + rng.uniform(-0.1, 0.1, x.shape) * cell
        y = y + rng.uniform(-0.1, 0.1, y.shape) * cell
        hgt, fx, fy, px, py = (rng.uniform(0.05, 0.3), *rng.uniform(2, 6, 2),
                               *rng.uniform(0, 2 * np.pi, 2))
        z = hgt * np.sin(fx * x + px) * np.cos(fy * y + py)
        P = np.c_[x, y, z] - 0.5
        Q, R = np.linalg.qr(rng.normal(size=(3, 3)))
        Q = Q * np.sign(np.diag(R))
        if np.linalg.det(Q) < 0:
            Q[:, 0] = -Q[:, 0]
        ijk = np.array([k % side, (k // side) % side, k // (side * side)], dtype=np.float64)
        P = P @ Q.T + 2.0 * ijk
        used, inv = np.unique(F, return_inverse=True)
        Vs.append(P[used])
        Fs.append(inv.reshape(-1, 3) + off)
        off += len(used)
    return write_obj(out, np.concatenate(Vs), np.concatenate(Fs))
