"""Write a few coarse closed meshes (a few dozen to a few hundred faces) as OFF files, for
``bench_seams.py``: the mean conformal distortion of automatic seams on low-poly meshes.

    python benchmarks/make_coarse_meshes.py OUTDIR

icosphere-80 and -320, UV sphere 16x8, cylinder 16, capsule (trimesh.creation) and two tori of
revolution (12x8 and 24x12 grids), the same shapes as ``tests/core/test_seams_coarse.py``.
"""
import os
import sys

import numpy as np
import trimesh


def torus(R, r, nu, nv):
    """Torus of revolution as a triangulated nu x nv grid, (V, F) outward oriented."""
    u = 2 * np.pi * np.arange(nu) / nu
    v = 2 * np.pi * np.arange(nv) / nv
    U, W = np.meshgrid(u, v, indexing="ij")
    V = np.stack([(R + r * np.cos(W)) * np.cos(U), (R + r * np.cos(W)) * np.sin(U),
                  r * np.sin(W)], axis=-1).reshape(-1, 3)
    idx = np.arange(nu * nv).reshape(nu, nv)
    b = np.roll(idx, -1, axis=0)
    c = np.roll(b, -1, axis=1)
    d = np.roll(idx, -1, axis=1)
    F = np.concatenate([np.stack([idx, b, c], -1).reshape(-1, 3),
                        np.stack([idx, c, d], -1).reshape(-1, 3)])
    return V, F


def meshes():
    """name -> (V, F) of every coarse mesh."""
    def tm(m):
        m.merge_vertices()
        return np.asarray(m.vertices), np.asarray(m.faces)
    return {
        "icosphere-80": tm(trimesh.creation.icosphere(subdivisions=1)),
        "icosphere-320": tm(trimesh.creation.icosphere(subdivisions=2)),
        "uv-sphere-16x8": tm(trimesh.creation.uv_sphere(count=[16, 8])),
        "cylinder-16": tm(trimesh.creation.cylinder(radius=1.0, height=2.0, sections=16)),
        "capsule": tm(trimesh.creation.capsule(height=2.0, radius=1.0, count=[16, 8])),
        "torus-12x8": torus(1.5, 0.9, 12, 8),
        "torus-24x12": torus(2.0, 0.7, 24, 12),
    }


def main(argv=None):
    argv = sys.argv[1:] if argv is None else argv
    if len(argv) != 1:
        print(__doc__)
        return 2
    os.makedirs(argv[0], exist_ok=True)
    for name, (V, F) in meshes().items():
        path = os.path.join(argv[0], name + ".off")
        trimesh.Trimesh(V, F, process=False).export(path)
        print(path, len(F), "faces")
    return 0


if __name__ == "__main__":
    sys.exit(main())
