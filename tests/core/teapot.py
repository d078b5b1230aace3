"""The Utah teapot as authored: Newell's 32 bicubic Bezier patches (``tests/data/teapot.bpt``,
public domain) evaluated on an n x n grid each, welded into one quad mesh of 4 open parts
(body with its bottom, handle, spout, lid; the lid's knob closes on a ring of radius 0.002).

Shared by ``tests/core`` and ``tests/blender`` (loaded by path there).
"""
import os
from math import comb

import numpy as np

DATA = os.path.join(os.path.dirname(os.path.dirname(__file__)), "data", "teapot.bpt")


def read_bpt(path=DATA):
    """(32,16) int patches (0-based) and (306,3) float control points of a ``.bpt`` file."""
    with open(path) as f:
        rows = [line.strip() for line in f if line.strip()]
    n = int(rows[0])
    patches = np.array([[int(x) for x in r.split(",")] for r in rows[1:1 + n]]) - 1
    k = int(rows[1 + n])
    points = np.array([[float(x) for x in r.split(",")] for r in rows[2 + n:2 + n + k]])
    return patches, points


def teapot(n=6, weld=1e-9):
    """The welded quad mesh: (V (k,3) float64, polygons: list of vertex index tuples).

    A quad with two corners welded together (at the lid's and bottom's poles) becomes a
    triangle; vertices are welded when closer than ``weld`` (patch seams repeat them).
    """
    patches, points = read_bpt()
    t = np.linspace(0.0, 1.0, n + 1)
    B = np.stack([comb(3, i) * t ** i * (1 - t) ** (3 - i) for i in range(4)], 1)  # (n+1,4)
    ctrl = points[patches].reshape(-1, 4, 4, 3)
    P = np.einsum("ui,vj,pijc->puvc", B, B, ctrl).reshape(-1, 3)
    key = np.round(P / weld).astype(np.int64)
    _, first, inv = np.unique(key, axis=0, return_index=True, return_inverse=True)
    order = np.argsort(first)                       # vertices in order of first appearance
    rank = np.empty_like(order)
    rank[order] = np.arange(len(order))
    V = P[first[order]]
    ids = rank[inv.ravel()].reshape(len(patches), n + 1, n + 1)
    i, j = np.meshgrid(np.arange(n), np.arange(n), indexing="ij")
    q = np.stack([ids[:, i, j], ids[:, i + 1, j], ids[:, i + 1, j + 1], ids[:, i, j + 1]], -1)
    polys = []
    for quad in q.reshape(-1, 4).tolist():          # test data: a few hundred faces
        out = [v for k, v in enumerate(quad) if v != quad[k - 1]]
        if len(set(out)) >= 3:
            polys.append(tuple(out))
    return V, polys


def triangulated(n=6):
    """(V, F (m,3) int64) with each quad cut along its first diagonal."""
    V, polys = teapot(n)
    F = [(p[0], p[k], p[k + 1]) for p in polys for k in range(1, len(p) - 1)]
    return V, np.asarray(F, dtype=np.int64)
