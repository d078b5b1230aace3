"""CPU time of writing an unwrapped OBJ: ``write_obj`` (vertices and triangles, what an OBJ
input got before) against ``write_unwrapped`` (an OBJ input's own text with its UVs replaced,
``bd_uv.obj.patched_obj``), least of 3 rounds, interleaved, on an n x n grid of quads with a
normal, a material and a smoothing group; the read (``load_mesh``) for scale.

    BD_UV_THREADS=1 python3.11 benchmarks/bench_obj_write.py [n]   (default 300: 90k quads)
"""
import os
import sys
import tempfile
import time

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
from bd_uv.meshio import load_mesh, write_obj, write_unwrapped  # noqa: E402


def quad_grid_obj(path, n):
    x, y = np.meshgrid(np.arange(n + 1), np.arange(n + 1))
    V = np.column_stack([x.ravel(), y.ravel(), 0.01 * np.sin(x.ravel() + y.ravel())])
    i = (np.arange(n)[:, None] * (n + 1) + np.arange(n)[None, :]).ravel()
    Q = np.stack([i, i + 1, i + n + 2, i + n + 1], 1) + 1
    with open(path, "w") as fh:
        fh.write("mtllib a.mtl\no grid\n")
        fh.writelines(f"v {a!r} {b!r} {c!r}\n" for a, b, c in V.tolist())
        fh.write("vn 0 0 1\nusemtl m\ns 1\n")
        fh.writelines(f"f {a}//1 {b}//1 {c}//1 {d}//1\n" for a, b, c, d in Q.tolist())


def main(n=300):
    with tempfile.TemporaryDirectory() as tmp:
        path = os.path.join(tmp, "grid.obj")
        quad_grid_obj(path, n)
        t = time.process_time()
        mesh = load_mesh(path)
        read = time.process_time() - t
        uv, F_uv = mesh.V[:, :2] / n, mesh.F.copy()     # any UVs: one vt per vertex
        best = {"write_obj": np.inf, "patched": np.inf}
        for _ in range(3):
            t = time.process_time()
            write_obj(os.path.join(tmp, "a.obj"), mesh.V, mesh.F, uv, F_uv)
            best["write_obj"] = min(best["write_obj"], time.process_time() - t)
            t = time.process_time()
            write_unwrapped(os.path.join(tmp, "b.obj"), path, mesh, uv, F_uv)
            best["patched"] = min(best["patched"], time.process_time() - t)
    print("| quads | read s | write_obj s | patched s | patched / write_obj |")
    print("|---|---|---|---|---|")
    print(f"| {n * n} | {read:.2f} | {best['write_obj']:.2f} | {best['patched']:.2f} | "
          f"{best['patched'] / best['write_obj']:.2f} |")


if __name__ == "__main__":
    main(*(int(a) for a in sys.argv[1:]))
