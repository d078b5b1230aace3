"""Grouped packing: coverage and time with ``--group material`` against no grouping.

For each mesh: the product's charts (seams auto, C = 2, S = 2), each face given one of
``--groups`` materials by its centroid's height (equal bands of z), then packed at 1024 px, 4 px
padding without grouping and with grouping by material. Printed per mesh: charts, groups,
coverage and seconds of both, certified, the least distance between two groups' convex hulls in
texels, and whether any chart enters another group's hull.

    PYTHONPATH=$PWD python3.11 benchmarks/bench_groups.py [--meshes cow.off] [--groups 3]
"""
import argparse
import os
import sys

import numpy as np
import shapely

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
from bd_uv.packing import PackOptions, layout_certificate, pack_islands  # noqa: E402
from bd_uv.packing.groups import chart_groups  # noqa: E402
from bench_pinned import each_mesh  # noqa: E402


def hull_figures(uv, lab, group_of_chart, resolution):
    """Least distance between two groups' convex hulls (texels), and whether a chart of another
    group meets a group's hull."""
    g = group_of_chart[lab]
    names = np.unique(g)
    hulls = [shapely.convex_hull(shapely.multipoints(uv[g == b].reshape(-1, 2))) for b in names]
    least = min((hulls[a].distance(hulls[b]) for a in range(len(names))
                 for b in range(a + 1, len(names))), default=np.inf) * resolution
    enters = any(shapely.intersects(h, shapely.polygons(uv[g != b])).any()
                 for b, h in zip(names, hulls))
    return least, enters


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--meshes", nargs="+", default=["suzanne.obj", "cow.off", "dino.off"])
    ap.add_argument("--groups", type=int, default=3)
    a = ap.parse_args()
    print(f"load {os.getloadavg()[0]:.1f}")
    print("mesh charts groups | none: coverage s | material: coverage s certified | "
          "hull gap px, chart in another group's hull | coverage ratio")
    for name, m, uv, lab in each_mesh(a.meshes):
        z = m.V[m.F].mean(axis=1)[:, 2]
        cuts = np.quantile(z, np.linspace(0, 1, a.groups + 1)[1:-1])
        material = np.searchsorted(cuts, z)
        k = int(lab.max()) + 1
        tile = np.full(k, 1001)
        free = pack_islands(m.V, m.F, uv, lab, PackOptions())
        c0 = layout_certificate(m.V, m.F, free.corner_uv.astype(np.float32), lab, tile, 1024, 4)
        grouped = pack_islands(m.V, m.F, uv, lab, PackOptions(group="material"),
                               face_labels={"material": material})
        out = grouped.corner_uv.astype(np.float32)
        c1 = layout_certificate(m.V, m.F, out, lab, tile, 1024, 4)
        g = chart_groups(m.F, m.V, lab, material, k)
        least, enters = hull_figures(out.astype(np.float64), lab, g, 1024)
        print(f"{name} {k} {int(g.max()) + 1} | {c0.coverage:.3f} {free.seconds:.2f} | "
              f"{c1.coverage:.3f} {grouped.seconds:.2f} {c1.certified} | {least:.2f}, {enters} | "
              f"{c1.coverage / c0.coverage:.3f}x", flush=True)
    print(f"load {os.getloadavg()[0]:.1f}")


if __name__ == "__main__":
    main()
