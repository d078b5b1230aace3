"""Packing around pinned charts: coverage before (the largest free square beside the pinned
charts' boxes, the previous method) and after (the free space around their shapes).

For each mesh: the product's charts (seams auto, C = 2, S = 2), a first pack of all of them, then
``--pin`` charts pinned where the first pack put them (every ``len // pin``-th by area, so large
and small ones), and the rest packed again both ways. Printed per mesh: charts, pinned, coverage
of the whole square (pinned + moved) before and after, the moved charts' density ratio, least
gap in texels, certified, seconds.

    PYTHONPATH=$PWD python3.11 benchmarks/bench_pinned.py [--meshes cow.off dino.off] [--pin 4]
"""
import argparse
import os
import sys
import time
from dataclasses import replace

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
from bd_uv.meshio import load_mesh  # noqa: E402
from bd_uv.packing import PackOptions, layout_certificate, pack_islands  # noqa: E402
from bd_uv.packing.pinned import chart_boxes, free_square  # noqa: E402

SHARED = "/work/shared/meshes"


def charts(V, F):
    """The product's charts (seams auto, C = 2, S = 2) stored as float32: (corner_uv, label)."""
    from bd_uv.layout import stored_layout
    from bd_uv.seams import unwrap_auto
    res = unwrap_auto(V, F, bound=2.0, stretch=2.0)[0]
    lay = stored_layout(V, F, res, pack=False, dtype=np.float32)
    return lay.corner_uv.astype(np.float64), lay.face_island


def each_mesh(names):
    """(name, mesh, corner_uv, label) of the product's charts of each named shared mesh."""
    for name in names:  # per mesh
        m = load_mesh(os.path.join(SHARED, name))
        uv, lab = charts(m.V, m.F)
        yield name, m, uv, lab


def free_square_pack(V, F, uv, lab, pinned, options):
    """The previous method: the moving charts nested into the largest square beside the pinned
    charts' bounding boxes."""
    t0 = time.perf_counter()
    k = int(lab.max()) + 1
    lo, hi = chart_boxes(uv, lab, np.flatnonzero(pinned))
    corner, side = free_square(lo, hi, 0.5 * options.padding)
    if side * options.resolution < 8 * max(options.padding_px, 1.0):
        return None, 0.0, time.perf_counter() - t0   # it refused: "no room left beside ..."
    sub = np.full(k, -1)
    sub[~pinned] = np.arange(int((~pinned).sum()))
    sl = np.where(lab >= 0, sub[np.maximum(lab, 0)], -1)
    inner = pack_islands(V, F, uv, sl, replace(options, padding_px=options.padding_px / side))
    out = uv.copy()
    out[sl >= 0] = inner.corner_uv[sl >= 0] * side + corner
    return out, inner.texel_density * side, time.perf_counter() - t0


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--meshes", nargs="+", default=["suzanne.obj", "cow.off", "dino.off",
                                                    "camel.off", "armadillo.off"])
    ap.add_argument("--pin", type=int, default=4)
    ap.add_argument("--resolution", type=int, default=1024)
    ap.add_argument("--padding", type=float, default=4.0)
    a = ap.parse_args()
    options = PackOptions(resolution=a.resolution, padding_px=a.padding)
    print(f"load {os.getloadavg()[0]:.1f}")
    print("mesh charts pinned | first pack (nothing pinned) coverage | before: coverage gap_px s "
          "| after: coverage gap_px s certified | after/before coverage, moved density")
    for name, m, uv, lab in each_mesh(a.meshes):
        k = int(lab.max()) + 1
        first = pack_islands(m.V, m.F, uv, lab, options).corner_uv
        c_first = layout_certificate(m.V, m.F, first.astype(np.float32), lab, np.full(k, 1001),
                                     a.resolution, a.padding)
        area = np.bincount(lab[lab >= 0], minlength=k)
        pinned = np.zeros(k, bool)
        pinned[np.argsort(-area)[::max(k // a.pin, 1)][:a.pin]] = True
        tile = np.full(k, 1001)
        old, d_old, s_old = free_square_pack(m.V, m.F, first, lab, pinned, options)
        if old is None:   # the previous method refused: only the pinned charts' coverage
            old = np.where(pinned[lab][:, None, None], first, np.nan)
        held = np.where(np.isfinite(old).all(axis=(1, 2)), lab, -1)
        c_old = layout_certificate(m.V, m.F, old.astype(np.float32), held, tile, a.resolution,
                                   a.padding)
        new = pack_islands(m.V, m.F, first, lab, options, pinned=pinned)
        assert np.array_equal(new.corner_uv[pinned[lab]], first[pinned[lab]])
        c_new = layout_certificate(m.V, m.F, new.corner_uv.astype(np.float32), lab, tile,
                                   a.resolution, a.padding)
        print(f"{name} {k} {int(pinned.sum())} | {c_first.coverage:.3f} | {c_old.coverage:.3f} {c_old.least_gap_px:.2f} "
              f"{s_old:.2f} | {c_new.coverage:.3f} {c_new.least_gap_px:.2f} {new.seconds:.2f} "
              f"{c_new.certified} | {c_new.coverage / c_old.coverage:.3f}x, "
              f"{new.texel_density / d_old if d_old else np.inf:.3f}x", flush=True)
    print(f"load {os.getloadavg()[0]:.1f}")


if __name__ == "__main__":
    main()
