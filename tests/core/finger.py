"""A glove finger: a flat annulus (outer radius R, inner r0) continued by a tube of radius r0 and
a hemispherical cap, triangulated as a surface of revolution. Topologically a disk (its one
boundary loop is the outer circle).

Its free-boundary conformal map shrinks the tube exponentially towards the cap (by about
``exp(-length / r0)``: a tube of modulus length / (2 pi r0) maps to an annulus of that modulus), so
at ``length = 12`` the cap's faces are ~5e-6 of the island's scale: certified in float64 at
C ~ 1.2, they collapse or flip once the island is packed into the unit square and rounded to
float32. A stretch limit (``unwrapping.storage``) keeps them apart.
"""
import numpy as np


def finger(length=12.0, n_theta=24, R=3.0, r0=1.0):
    """(V (n,3) float64, F (m,3) int64) of the finger; faces about 2 pi r0 / n_theta wide."""
    h = 2.0 * np.pi * r0 / n_theta
    profile = [(r, 0.0) for r in np.arange(R, 1.5 * r0, -h)[:-1]]        # flat annulus
    f = 0.5 * r0                                                         # fillet into the tube
    for a in np.linspace(-0.5 * np.pi, -np.pi, max(3, int(0.5 * np.pi * f / h)) + 1)[:-1]:
        profile.append((r0 + f + f * np.cos(a), f + f * np.sin(a)))
    profile += [(r0, z) for z in np.arange(f, f + length, h)]           # the tube
    top = f + length
    for a in np.linspace(0.0, 0.5 * np.pi, max(3, int(0.5 * np.pi * r0 / h)) + 1)[:-1]:
        profile.append((r0 * np.cos(a), top + r0 * np.sin(a)))           # the cap
    P = np.array(profile)
    th = np.linspace(0.0, 2.0 * np.pi, n_theta, endpoint=False)
    V = np.concatenate([
        np.stack([np.outer(P[:, 0], np.cos(th)).ravel(), np.outer(P[:, 0], np.sin(th)).ravel(),
                  np.repeat(P[:, 1], n_theta)], axis=1),
        [[0.0, 0.0, top + r0]]])
    i, j = np.meshgrid(np.arange(len(P) - 1), np.arange(n_theta), indexing="ij")
    a = (i * n_theta + j).ravel()
    b = (i * n_theta + (j + 1) % n_theta).ravel()
    F = np.concatenate([np.stack([a, b, b + n_theta], 1), np.stack([a, b + n_theta, a + n_theta], 1)])
    ring = (len(P) - 1) * n_theta + np.arange(n_theta)
    cap = np.stack([ring, (len(P) - 1) * n_theta + (np.arange(n_theta) + 1) % n_theta,
                    np.full(n_theta, len(V) - 1)], 1)
    return V, np.concatenate([F, cap]).astype(np.int64)
