"""Benchmark the atlas packer: bd-uv's against Blender's Pack Islands on the same charts, and
xatlas on its own charts, in one run.

For each mesh the charts come from ``bd_uv.seams.unwrap_auto`` (``--seams auto --bound 2
--stretch 2``, the product's unwrap) and are stored as float32 (not timed). Then, at 1024 px and
4 px padding unless told otherwise:

- bd-uv: ``bd_uv.packing.pack_islands`` with ``PackOptions(resolution, padding_px)``; time is
  ``Packed.seconds`` (packing alone: outlines, nesting, placing);
- Blender (bpy): the charts as a mesh's UV map, ``uv.average_islands_scale()`` (not timed), then
  ``uv.pack_islands(shape_method=AABB|CONVEX|CONCAVE, rotate=True, rotate_method='ANY',
  margin_method='FRACTION', margin=padding / 2 / resolution)`` timed alone (Blender's margin goes
  around each island, so two islands end up about twice the margin apart);
- xatlas: ``Atlas.add_mesh`` and ``generate(ChartOptions(), PackOptions(padding, resolution))``
  on the mesh itself: its own charts and packing, both timed (the binding has no separate pack
  call); coverage of its own rectangle and of the square around it. xatlas may mirror charts.

Coverage is the UV area inside the atlas over the atlas's area; the least gap is the exact least
distance between two charts' UV boundaries (``bd_uv.packing.least_gaps``) in texels; every layout
is measured by the same code on its float32 UVs. Ratios ours / Blender's exact shape (CONCAVE).

Usage::

    python3.11 benchmarks/bench_pack.py [MESH ...] [--resolution 1024] [--padding 4]
        [--skip-convex]

Default meshes: suzanne, cow, dino, fandisk, camel, armadillo from /work/shared/meshes.
"""
import argparse
import os
import sys
import time

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))

from bd_uv.meshio import load_mesh  # noqa: E402
from bd_uv.packing import PackOptions, layout_certificate, least_gaps, pack_islands  # noqa: E402

MESHES = ["suzanne.obj", "cow.off", "dino.off", "fandisk.off", "camel.off", "armadillo.off"]
SHARED = "/work/shared/meshes"


def charts(V, F):
    """The product's charts (seams auto, C = 2, S = 2) stored as float32: (corner_uv, label)."""
    from bd_uv.layout import stored_layout
    from bd_uv.seams import unwrap_auto
    res = unwrap_auto(V, F, bound=2.0, stretch=2.0)[0]
    lay = stored_layout(V, F, res, pack=False, dtype=np.float32)
    return lay.corner_uv, lay.face_island


def measure(V, F, uv, lab, resolution, padding, tile=None):
    """Coverage of the unit square and least gap in texels, on float32 UVs."""
    k = int(lab.max()) + 1
    tile = np.full(k, 1001) if tile is None else tile
    c = layout_certificate(V, F, uv.astype(np.float32), lab, tile, resolution, padding)
    return c.coverage, c.least_gap_px, c.certified, c.reason


def run_ours(V, F, uv, lab, resolution, padding):
    p = pack_islands(V, F, uv, lab, PackOptions(resolution=resolution, padding_px=padding))
    return p.corner_uv, p.seconds, p.tile


_scene_ready = False


def run_blender(V, F, uv, lab, shape, resolution, padding):
    """Blender's Pack Islands on the charts as one mesh's UV map: (corner_uv, seconds)."""
    global _scene_ready
    import bpy
    if not _scene_ready:
        bpy.ops.wm.read_factory_settings(use_empty=True)
        _scene_ready = True
    keep = lab >= 0
    Fk = F[keep]
    me = bpy.data.meshes.new("charts")
    me.from_pydata(V.tolist(), [], Fk.tolist())
    me.update()
    layer = me.uv_layers.new(name="UV")
    layer.data.foreach_set("uv", uv[keep].reshape(-1).astype(np.float32))
    ob = bpy.data.objects.new("charts", me)
    bpy.context.scene.collection.objects.link(ob)
    for o in bpy.context.scene.objects:
        o.select_set(o is ob)
    bpy.context.view_layer.objects.active = ob
    bpy.ops.object.mode_set(mode="EDIT")
    bpy.ops.mesh.select_all(action="SELECT")
    bpy.ops.uv.select_all(action="SELECT")
    bpy.ops.uv.average_islands_scale()
    t = time.perf_counter()
    bpy.ops.uv.pack_islands(udim_source="CLOSEST_UDIM", rotate=True, rotate_method="ANY",
                            scale=True, merge_overlap=False, margin_method="FRACTION",
                            margin=padding / 2 / resolution, pin=False, shape_method=shape)
    seconds = time.perf_counter() - t
    bpy.ops.object.mode_set(mode="OBJECT")
    flat = np.empty(len(Fk) * 6, dtype=np.float32)
    me.uv_layers["UV"].data.foreach_get("uv", flat)
    bpy.data.objects.remove(ob)
    bpy.data.meshes.remove(me)
    out = np.full(uv.shape, np.nan)
    out[keep] = flat.reshape(-1, 3, 2)
    return out, seconds


def run_xatlas(V, F, resolution, padding):
    """xatlas's own charts and packing: (coverage of its rectangle, of its square, least gap px,
    seconds, charts)."""
    import xatlas
    from scipy.sparse import coo_array
    from scipy.sparse.csgraph import connected_components
    atlas = xatlas.Atlas()
    atlas.add_mesh(V.astype(np.float32), F.astype(np.uint32))
    po = xatlas.PackOptions()
    po.padding, po.resolution = int(round(padding)), int(resolution)
    t = time.perf_counter()
    atlas.generate(xatlas.ChartOptions(), po)
    seconds = time.perf_counter() - t
    _, idx, uvs = atlas[0]
    W, H = atlas.width, atlas.height
    P = uvs[idx].astype(np.float64) * (W, H)           # texels
    e1, e2 = P[:, 1] - P[:, 0], P[:, 2] - P[:, 0]
    area = 0.5 * np.abs(e1[:, 0] * e2[:, 1] - e1[:, 1] * e2[:, 0]).sum()
    # charts: faces joined by shared output vertices
    m = len(idx)
    rows = np.repeat(np.arange(m), 3)
    inc = coo_array((np.ones(3 * m), (rows, idx.ravel())), shape=(m, len(uvs))).tocsr()
    n, lab = connected_components(inc @ inc.T, directed=False)
    gap = float(least_gaps(idx, P, lab).min())
    return area / (W * H), area / max(W, H) ** 2, gap, seconds, n


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("meshes", nargs="*", default=[os.path.join(SHARED, m) for m in MESHES])
    ap.add_argument("--resolution", type=int, default=1024)
    ap.add_argument("--padding", type=float, default=4.0)
    ap.add_argument("--skip-convex", action="store_true", help="CONVEX is slow; leave it out")
    args = ap.parse_args(argv)
    shapes = ["AABB"] + ([] if args.skip_convex else ["CONVEX"]) + ["CONCAVE"]
    print(f"{args.resolution} px, padding {args.padding:g} px; cov = coverage, gap = least gap "
          f"in px, s = seconds of packing alone (xatlas: charts + packing)")
    rows = []
    for path in args.meshes:
        mesh = load_mesh(path)
        V, F = mesh.V, mesh.F
        uv, lab = charts(V, F)
        k = int(lab.max()) + 1
        out, sec, tile = run_ours(V, F, uv, lab, args.resolution, args.padding)
        ours = (*measure(V, F, out, lab, args.resolution, args.padding, tile), sec)
        line = [f"{mesh.name:10s} {len(F):6d} faces {k:4d} charts | bd-uv cov {ours[0]:.3f} "
                f"gap {ours[1]:5.2f} s {sec:6.2f}{'' if ours[2] else ' NOT CERTIFIED: ' + ours[3]}"]
        bl = {}
        for shape in shapes:
            bout, bsec = run_blender(V, F, uv, lab, shape, args.resolution, args.padding)
            cov, gap, _, _ = measure(V, F, bout, lab, args.resolution, args.padding)
            bl[shape] = (cov, gap, bsec)
            line.append(f"Blender {shape} cov {cov:.3f} gap {gap:5.2f} s {bsec:6.2f}")
        xr, xs, xg, xsec, xn = run_xatlas(V, F, args.resolution, args.padding)
        line.append(f"xatlas ({xn} charts) cov {xr:.3f} (square {xs:.3f}) gap {xg:5.2f} "
                    f"s {xsec:6.2f}")
        c = bl["CONCAVE"]
        line.append(f"ours/Blender-exact: coverage {ours[0] / c[0]:.3f}x, time "
                    f"{sec / c[2]:.3f}x; ours/xatlas coverage {ours[0] / xr:.3f}x")
        print("\n    ".join(line), flush=True)
        rows.append((ours[0] / c[0], sec / c[2], ours[0] / xr))
    r = np.array(rows)
    print(f"ours/Blender exact shape: coverage {r[:, 0].min():.3f}-{r[:, 0].max():.3f}x, time "
          f"{r[:, 1].min():.3f}-{r[:, 1].max():.3f}x; ours/xatlas coverage "
          f"{r[:, 2].min():.3f}-{r[:, 2].max():.3f}x")


if __name__ == "__main__":
    main()
