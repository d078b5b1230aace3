"""Benchmark meshes made from the shared meshes or from a seed, written as OBJ files.

Every asset is a file, so Blender and bd-uv read the same triangles in the same order, and the
same call with the same inputs writes the same file (a re-run reuses it):

- ``subdivided(path, times)``: ``trimesh.remesh.subdivide`` (each triangle into four) ``times``
  times: face.obj 51,712 -> 206,848 -> 827,392 faces; mannequin-devil 25,888 -> 103,552 -> 414,208.
- ``patch(path, faces)``: the smallest ball of whole face rings (breadth-first over shared edges)
  around the face nearest the vertex centroid holding at least ``faces`` faces: smaller meshes of
  the same surface (grown on until the rings close into a disk).
- ``ball(path, faces, at)``: the same rings round the face nearest the centre of one side of the
  bounding box (``at``: ``"top"`` = ``"y+"``, ``"x+"``, ``"z-"``, ...).
- ``strip(path, faces, axis)``: the same rings round a shortest face path between the faces
  nearest the centres of the two sides normal to ``axis``: a long thin disk.
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


def _face_graph(F):
    """Faces as a graph: a CSR matrix with an entry for each pair of faces sharing an edge."""
    import scipy.sparse as sp

    adj = _face_adjacency(F)
    m = len(F)
    return sp.coo_array((np.ones(2 * len(adj)), (np.r_[adj[:, 0], adj[:, 1]],
                                                 np.r_[adj[:, 1], adj[:, 0]])),
                        shape=(m, m)).tocsr()


def _rings_to_disk(V, F, ring, faces, out, what):
    """Keep the faces of whole rings (``ring``: each face's ring number, inf where unreached) up
    to the ring holding the ``faces``-th face, then more whole rings until they form a disk;
    write them as ``out`` (unreferenced vertices dropped, the file's face order)."""
    ring = np.where(np.isfinite(ring), ring, np.inf)
    levels = np.sort(ring[np.isfinite(ring)])
    r = levels[min(faces, len(levels)) - 1]
    keep = np.flatnonzero(ring <= r)
    for nxt in np.unique(levels[levels > r]):
        if is_disk(F[keep]):
            break
        keep = np.flatnonzero(ring <= nxt)
    if not is_disk(F[keep]):
        raise ValueError(f"{what}: no whole ring closes into a disk")
    sub = F[keep]
    used, inv = np.unique(sub, return_inverse=True)
    return write_obj(out, V[used], inv.reshape(-1, 3))


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
    from scipy.sparse.csgraph import shortest_path

    from measure import load_mesh_by_index

    V, F = load_mesh_by_index(path)
    cen = V[F].mean(axis=1)
    seed = int(np.argmin(np.linalg.norm(cen - V.mean(axis=0), axis=1)))
    ring = shortest_path(_face_graph(F), unweighted=True, indices=seed)
    return _rings_to_disk(V, F, ring, faces,
                          out, f"{path}: around its central face")


BOX_POINTS = {"top": (1, +1), "bottom": (1, -1), "x+": (0, +1), "x-": (0, -1),
              "y+": (1, +1), "y-": (1, -1), "z+": (2, +1), "z-": (2, -1)}


def _box_point(V, axis, side):
    """The centre of the side ``side`` (+1: max, -1: min) of the vertices' bounding box normal
    to ``axis``."""
    lo, hi = V.min(axis=0), V.max(axis=0)
    p = (lo + hi) / 2
    p[axis] = hi[axis] if side > 0 else lo[axis]
    return p


def _nearest_face(V, F, p):
    return int(np.argmin(np.linalg.norm(V[F].mean(axis=1) - p, axis=1)))


def ball(path: str, faces: int, at: str = "top", out_dir: str = DEFAULT_DIR) -> str:
    """Like :func:`patch`, but the rings grow round the face nearest a point of the bounding box.

    ``at`` names the point (``BOX_POINTS``): the centre of one side of the vertices' axis-aligned
    bounding box, ``"x+"`` the side at the largest x, ``"top"`` (= ``"y+"``) the largest y, and
    so on; the seed is the face whose centroid is nearest that point. Whole rings over shared
    edges, at least ``faces`` faces, grown on until a disk (ValueError if none is). Written as
    ``<stem>-ball<faces><at>.obj``; e.g. knight-ball3000top (3,028 faces), camel-ball300top (316),
    cow-ball150x+ (169) of issue21-unseen16-2026-11-28.md come out face for face.
    """
    out = os.path.join(out_dir, f"{_stem(path)}-ball{faces}{at}.obj")
    if os.path.exists(out):
        return out
    from scipy.sparse.csgraph import shortest_path

    from measure import load_mesh_by_index

    axis, side = BOX_POINTS[at]
    V, F = load_mesh_by_index(path)
    seed = _nearest_face(V, F, _box_point(V, axis, side))
    ring = shortest_path(_face_graph(F), unweighted=True, indices=seed)
    return _rings_to_disk(V, F, ring, faces, out, f"{path}: round its face at {at}")


def strip(path: str, faces: int, axis: str = "x", out_dir: str = DEFAULT_DIR) -> str:
    """A long thin disk: whole face rings round a face path across the mesh along ``axis``.

    The path's ends are the faces whose centroids are nearest the centres of the two sides of the
    vertices' bounding box normal to ``axis`` (``"x"``, ``"y"`` or ``"z"``); the path is the
    unweighted shortest path over shared edges from the end at the least coordinate, as
    ``scipy.sparse.csgraph.shortest_path``'s predecessors give it (ties broken its way). Ring n
    holds the faces n steps from the nearest face of the path; whole rings, at least ``faces``
    faces, grown on until a disk (ValueError if none is). Written as
    ``<stem>-strip<faces><axis>.obj``.
    """
    out = os.path.join(out_dir, f"{_stem(path)}-strip{faces}{axis}.obj")
    if os.path.exists(out):
        return out
    from scipy.sparse.csgraph import dijkstra

    from measure import load_mesh_by_index

    V, F = load_mesh_by_index(path)
    route = strip_route(V, F, axis, path)
    ring = dijkstra(_face_graph(F), unweighted=True, indices=route, min_only=True)
    return _rings_to_disk(V, F, ring, faces, out, f"{path}: round its path along {axis}")


def strip_route(V: np.ndarray, F: np.ndarray, axis: str, what: str = "the mesh") -> list[int]:
    """:func:`strip`'s face path: face indices from the end at the least ``axis`` coordinate to
    the end at the largest, each sharing an edge with the next."""
    from scipy.sparse.csgraph import shortest_path

    k = "xyz".index(axis)
    a, b = (_nearest_face(V, F, _box_point(V, k, side)) for side in (-1, +1))
    pred = shortest_path(_face_graph(F), unweighted=True, indices=a, return_predecessors=True)[1]
    if pred[b] < 0 and a != b:
        raise ValueError(f"{what}: its faces at the two ends of {axis} are not connected")
    route = [b]
    while route[-1] != a:
        route.append(int(pred[route[-1]]))
    return route[::-1]


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
