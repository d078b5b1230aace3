"""Independent reference computations and small meshes for the core tests.

Nothing here calls bd_uv's metrics: distortion is recomputed from singular values of the 2x2 map
between each triangle's own 2D shape and its UV triangle.
"""
import dataclasses
import os

import numpy as np

DATA = os.path.join(os.path.dirname(os.path.dirname(__file__)), "data")


def reference_jacobians(V, F, corner_uv):
    """(m,2,2) Jacobian of each face's map from its own 3D triangle (laid in 2D) to its UVs."""
    P = np.asarray(V, float)[np.asarray(F)]
    e1, e2 = P[:, 1] - P[:, 0], P[:, 2] - P[:, 0]
    x = e1 / np.linalg.norm(e1, axis=1)[:, None]
    n = np.cross(e1, e2)
    y = np.cross(n / np.linalg.norm(n, axis=1)[:, None], x)
    S = np.stack([np.stack([np.einsum("ij,ij->i", e1, x), np.einsum("ij,ij->i", e1, y)], 1),
                  np.stack([np.einsum("ij,ij->i", e2, x), np.einsum("ij,ij->i", e2, y)], 1)], 2)
    uv = np.asarray(corner_uv, float)
    T = np.stack([uv[:, 1] - uv[:, 0], uv[:, 2] - uv[:, 0]], 2)  # columns: UV edges
    return T @ np.linalg.inv(S)


def reference_distortion(V, F, corner_uv):
    """(D, flipped): D = s_max / s_min of each face's Jacobian (numpy SVD), flipped = det <= 0."""
    J = reference_jacobians(V, F, corner_uv)
    s = np.linalg.svd(J, compute_uv=False)
    det = np.linalg.det(J)
    with np.errstate(divide="ignore"):
        D = s[:, 0] / s[:, 1]
    return D, det <= 0


def float32_flat(V, F):
    """(m,) bool: faces too thin for float32, by this test's own sums: twice the area (a cross
    product's norm) at most one float32 step of the largest coordinate times the longest edge
    (positions cannot tell the face from a line), or at most 2^-24 (float32's step in [0.5, 1))
    times the square root of the area of all of ``F`` times the longest edge (at the scale that
    fills the unit square keeping every face's area the face is under one UV step high), or at
    most 1e-12 times the longest edge squared. ``F`` is the whole mesh. The scene writers leave
    such faces out of the certificate (their corners take neighbouring UVs)."""
    P = np.asarray(V, np.float64)[np.asarray(F)]
    a2 = np.linalg.norm(np.cross(P[:, 1] - P[:, 0], P[:, 2] - P[:, 0]), axis=1)
    edges = np.linalg.norm(P - np.roll(P, 1, axis=1), axis=2).max(axis=1)
    step = np.spacing(np.abs(P).max(axis=(1, 2)).astype(np.float32)).astype(np.float64)
    uv_step = 2.0 ** -24 * np.sqrt(0.5 * a2[np.isfinite(a2)].sum())
    return (a2 <= np.maximum(step, uv_step) * edges) | (a2 <= 1e-12 * edges ** 2)


def grid(nx=6, ny=5, z=None):
    """A planar (or height-field) triangulated grid, (V, F)."""
    xs, ys = np.meshgrid(np.linspace(0, 1, nx), np.linspace(0, 0.8, ny))
    zs = np.zeros_like(xs) if z is None else z(xs, ys)
    V = np.stack([xs.ravel(), ys.ravel(), zs.ravel()], 1)
    i = np.arange(nx * ny).reshape(ny, nx)
    a, b, c, d = i[:-1, :-1].ravel(), i[:-1, 1:].ravel(), i[1:, :-1].ravel(), i[1:, 1:].ravel()
    F = np.concatenate([np.stack([a, b, d], 1), np.stack([a, d, c], 1)])
    return V, F


def load_off(name):
    with open(os.path.join(DATA, name)) as fh:
        tok = fh.read().split()
    assert tok[0] == "OFF"
    nv, nf = int(tok[1]), int(tok[2])
    V = np.array(tok[4:4 + 3 * nv], float).reshape(nv, 3)
    rest = np.array(tok[4 + 3 * nv:4 + 3 * nv + 4 * nf], int).reshape(nf, 4)
    return V, rest[:, 1:]


def rings(V, F, seed, faces):
    """Whole rings of faces around the face ``seed``, grown over shared edges until at least
    ``faces`` faces: a disk cut from a larger mesh."""
    import scipy.sparse as sp
    from scipy.sparse.csgraph import shortest_path
    e = np.sort(np.stack([F, np.roll(F, -1, axis=1)], axis=2).reshape(-1, 2), axis=1)
    key = e[:, 0] * len(V) + e[:, 1]
    order = np.argsort(key, kind="stable")
    same = np.flatnonzero(key[order][1:] == key[order][:-1])
    a, b = order[same] // 3, order[same + 1] // 3
    A = sp.coo_array((np.ones(2 * len(a)), (np.r_[a, b], np.r_[b, a])),
                     shape=(len(F), len(F))).tocsr()
    ring = shortest_path(A, unweighted=True, indices=seed)
    keep = np.flatnonzero(ring <= np.sort(ring)[faces - 1])
    used, inv = np.unique(F[keep], return_inverse=True)
    return V[used], inv.reshape(-1, 3)


def same_certificate(a, b):
    """Two certificates equal field by field, NaN equal to NaN. A dataclass's ``==`` compared
    its fields as one tuple up to Python 3.12, where a NaN default (``min_singular``) equals
    itself by identity; from Python 3.13 (Blender 5.1+) it compares field by field, NaN != NaN."""
    fa, fb = dataclasses.astuple(a), dataclasses.astuple(b)
    return type(a) is type(b) and all(
        x == y or (isinstance(x, float) and isinstance(y, float) and x != x and y != y)
        for x, y in zip(fa, fb))


def relpath_across_drives(name):
    """``os.path.relpath`` as on Windows when a path naming ``name`` is on another drive than
    the start: it raises ValueError there."""
    relpath = os.path.relpath

    def across(path, start=os.curdir):
        if name in str(path):
            raise ValueError("path is on mount 'C:', start on mount 'D:'")
        return relpath(path, start)
    return across
