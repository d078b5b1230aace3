"""Cost of the overlap certificate: its share of the unwrap time on a real mesh, and its time on
a strip with 200k boundary edges (overlap-free and overlapping).

    python3.11 benchmarks/overlap_check.py [MESH]   (default /work/shared/meshes/face.obj)
"""
import os
import sys
import time

import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "tests", "core"))

import bd_uv  # noqa: E402
from bd_uv.layout import stored_layout  # noqa: E402
from bd_uv.overlap import island_overlaps  # noqa: E402
from overlap_shapes import spiral_uv  # noqa: E402


def best(f, repeat=3):
    times = []
    for _ in range(repeat):
        t = time.perf_counter()
        out = f()
        times.append(time.perf_counter() - t)
    return min(times), out


def main(path):
    mesh = bd_uv.load_mesh(path)
    t = time.perf_counter()
    res = bd_uv.unwrap(mesh.V, mesh.F, bound=5.0)
    t_unwrap = time.perf_counter() - t
    bounds = [r.bound_certified for r in res.islands]
    t_ov, ov = best(lambda: island_overlaps(mesh.F, res.corner_uv, res.face_island))
    t_cert, _ = best(lambda: bd_uv.certify_islands(mesh.V, mesh.F, res.corner_uv,
                                                   res.face_island, bounds))
    t_lay, _ = best(lambda: stored_layout(mesh.V, mesh.F, res, pack=True, cut=True))
    print(f"load average {os.getloadavg()[0]:.1f} on {os.cpu_count()} cores")
    print(f"{os.path.basename(path)}: {len(mesh.F)} faces, {len(ov.boundary.p)} boundary edges")
    print(f"  unwrap {t_unwrap:.2f} s; overlap check {t_ov:.3f} s "
          f"({100 * t_ov / t_unwrap:.2f} %); certify_islands {t_cert:.3f} s "
          f"({100 * t_cert / t_unwrap:.2f} %); cut+pack+certify {t_lay:.3f} s "
          f"({100 * t_lay / t_unwrap:.2f} %)")
    for turns in (0.8, 2.5):
        V, F, uv = spiral_uv(turns, n=100_000, width=0.3)
        lab = np.zeros(len(F), dtype=np.int64)
        t_ov, ov = best(lambda: island_overlaps(F, uv, lab))
        t_cert, c = best(lambda: bd_uv.certify_islands(V, F, uv, lab, [100.0]))
        print(f"spiral strip {turns} turns: {len(F)} faces, {len(ov.boundary.p)} boundary edges, "
              f"overlap-free {bool(ov.overlap_free[0])}, crossings {int(ov.crossings[0])}: "
              f"overlap check {t_ov:.3f} s, certify_islands {t_cert:.3f} s")


if __name__ == "__main__":
    main(sys.argv[1] if len(sys.argv) > 1 else "/work/shared/meshes/face.obj")
