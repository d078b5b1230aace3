"""How far a two-chart atlas is from the best square any packer can reach on the same charts.

    python benchmarks/two_chart_optimum.py MESH [MESH ...] [--resolution 1024] [--padding 4]

For each mesh: the product's charts (``bench_pack.charts``: seams auto, C = 2, S = 2, stored as
float32), packed by ``bd_uv.packing.pack_islands`` (coverage from the layout certificate), and,
when there are two charts, a near-exhaustive search for the least square holding both:

- each chart's exact outer outline (as the packer sees it), grown by half the padding (mitred);
- every turn of the first chart in [0, 90) degrees (a quarter turn of both is the same square)
  and of the second in [0, 360), on a 5-degree grid, then a 1-degree grid within 5 degrees of
  the best pair;
- for a turn pair, every offset of the second chart against the first on a raster (the side
  found by the packer is 128 cells on the coarse grid, 256 on the fine one): an FFT correlation
  of the two rasters gives the offsets where they do not meet, and for each such offset the
  square's side is the larger extent of the pair's bounding box.

A cell is in a raster when its centre is in the grown outline, so the search is an estimate,
not a bound: at 256 cells to the side it can err by about a cell each way (~1.5 % of coverage).
It answers one question of issue 18: whether ">= 1.05x Blender's exact-shape packer" is
reachable on a two-chart set at all, when both packers are within a few per cent of the best
square. It is a measurement: nothing here is used by the product.
"""
from __future__ import annotations

import argparse
import os
import sys
import time

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.dirname(HERE))
sys.path.insert(0, HERE)

import bd_uv  # noqa: E402
from bd_uv.packing import PackOptions  # noqa: E402
from bd_uv.packing.outlines import chart_outlines  # noqa: E402
from bench_pack import charts, measure, run_ours  # noqa: E402


def _raster(poly, h, n):
    """Cells of an n x n raster of side h from the outline's low corner whose centre it holds;
    the outline's width and height in cells."""
    import shapely
    x0, y0, x1, y1 = poly.bounds
    c = h * (np.arange(n) + 0.5)
    X, Y = np.meshgrid(x0 + c, y0 + c, indexing="xy")
    cells = shapely.contains_xy(poly, X.ravel(), Y.ravel()).reshape(n, n).astype(np.float64)
    return cells, int(np.ceil((x1 - x0) / h)), int(np.ceil((y1 - y0) / h))


def least_side(polys, side, cells, turns_a, turns_b):
    """The least square side (in the charts' units) over the turn pairs, and the best pair."""
    from shapely import affinity
    h = side / cells
    n = 2 * cells                      # a chart fits in the square: at most `cells` wide
    size = (2 * n, 2 * n)

    def spectrum(poly, turn, flip):
        r, w, t = _raster(affinity.rotate(poly, turn, origin=(0, 0)), h, n)
        return np.fft.rfft2(r[::-1, ::-1] if flip else r, s=size), w, t

    first = {a: spectrum(polys[0], a, False) for a in turns_a}
    second = {b: spectrum(polys[1], b, True) for b in turns_b}
    d = np.arange(2 * n) - (n - 1)     # the second chart's offset from the first, in cells
    best = (np.inf, None)
    for a, (fa, wa, ha) in first.items():
        for b, (fb, wb, hb) in second.items():
            apart = np.fft.irfft2(fa * fb, s=size) < 0.5
            sx = np.maximum(np.maximum(wa - d, d + wb), max(wa, wb))
            sy = np.maximum(np.maximum(ha - d, d + hb), max(ha, hb))
            s = np.where(apart, np.maximum(sx[None, :], sy[:, None]), np.inf).min()
            if s < best[0]:
                best = (s, (float(a), float(b)))
    return best[0] * h, best[1]


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("meshes", nargs="+")
    ap.add_argument("--resolution", type=int, default=1024)
    ap.add_argument("--padding", type=float, default=4.0)
    args = ap.parse_args(argv)
    import shapely
    print("| mesh | charts | ours | best square found | ours / best | turns (deg) | search s |")
    print("|---|---|---|---|---|---|---|")
    for path in args.meshes:
        mesh = bd_uv.load_mesh(path)
        uv, lab = charts(mesh.V, mesh.F)
        k = int(lab.max()) + 1
        packed, _, tile = run_ours(mesh.V, mesh.F, uv, lab, args.resolution, args.padding)
        ours = measure(mesh.V, mesh.F, packed, lab, args.resolution, args.padding, tile)[0]
        name = os.path.basename(path)
        if k != 2:
            print(f"| {name} | {k} | {ours:.3f} | (two charts only) | | | |")
            continue
        t = time.perf_counter()
        opts = PackOptions(resolution=args.resolution, padding_px=args.padding)
        ch, _ = chart_outlines(mesh.V, mesh.F, uv, lab, k, opts)
        area = float(ch.area.sum())
        side = float(np.sqrt(area / ours))        # the packer's side, in the charts' units
        grow = 0.5 * args.padding / args.resolution * side
        polys = [shapely.Polygon(e).buffer(grow, join_style="mitre") for e in ch.exact]
        s1, (a, b) = least_side(polys, side, 128, np.arange(0, 90, 5.0), np.arange(0, 360, 5.0))
        s2, turns = least_side(polys, side, 256, np.arange(a - 5, a + 6, 1.0),
                               np.arange(b - 5, b + 6, 1.0))
        best = area / min(s1, s2) ** 2
        print(f"| {name} | 2 | {ours:.3f} | {best:.3f} | {ours / best:.3f} | {turns} | "
              f"{time.perf_counter() - t:.0f} |", flush=True)


if __name__ == "__main__":
    main()
