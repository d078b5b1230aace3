"""Live editing (``bd_uv.LiveSession``) on real disks, beside Blender's own per-frame Live Unwrap.

Per mesh: the rest shape is ``bd_uv.unwrap(V, F, bound=5, overlap="fail")`` (one certified,
overlap-free island); two pins, the vertices nearest the rest shape's centre -/+ 0.3 of its width,
are turned about their midpoint by up to 150 degrees and pulled apart to 1.3x over 20 frames, then
brought back over 20 more. Printed per mesh:

- set-up (``LiveSession(...)``: certificate, factorisation) and the per-frame ``update`` latency
  (median, p95, max) in milliseconds, with the pin error (largest, relative to the island's size)
  and the frames certified; every frame is also re-checked outside the session, untimed:
  ``bd_uv.conformal_distortion`` against the rest shape, ``bd_uv.flipped_faces`` and
  ``bd_uv.island_overlaps`` on the frame's corner UVs;
- Blender's Live Unwrap cost for the same drag through the bpy module: the pinned UVs set to the
  frame's targets (untimed), then ``bpy.ops.uv.unwrap(method="CONFORMAL", margin=0)`` with those
  pins, timed per frame; and its median over ours, measured in the same run;
- the CPU time of each update (``time.thread_time``: what the frame costs whatever else runs on
  the machine) beside its wall time, and the load average before each mesh (on a shared machine
  compare ratios and CPU time, not wall seconds).

Targets on a 2-core machine (issue 19): ~10k faces median <= 33 ms and p95 <= 100 ms; ~30k faces
median <= 100 ms and p95 <= 250 ms.

    python3.11 benchmarks/bench_live.py                      # the five disks and a 10k patch
    python3.11 benchmarks/bench_live.py --no-blender lion-head.off
    python3.11 benchmarks/bench_live.py --big          # also mannequin-devil subdivided (103k)
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

import assets  # noqa: E402
from measure import load_mesh_by_index  # noqa: E402

import bd_uv  # noqa: E402

MESH_DIR = "/work/shared/meshes"
DEFAULT = ["nefertiti.off", "three_peaks.off", "face.obj@patch10000", "lion-head.off",
           "mannequin-devil.off", "face.obj"]


def mesh_path(spec):
    """``name``, ``name@patchN`` (a disk of about N faces from its centre) or ``name@subN``."""
    name, _, how = spec.partition("@")
    path = name if os.path.isabs(name) else os.path.join(MESH_DIR, name)
    if how.startswith("patch"):
        return assets.patch(path, int(how[5:]))
    if how.startswith("sub"):
        return assets.subdivided(path, int(how[3:]))
    return path


def drag(P0, frames):
    """Targets (frames, 2, 2): turned up to 150 degrees and pulled to 1.3x, then back."""
    half = frames // 2
    f = np.concatenate([np.arange(1, half + 1) / half, np.arange(half - 1, -1, -1) / half])
    mid = P0.mean(axis=0)
    out = []
    for x in f[:frames]:
        a = np.deg2rad(150.0) * x
        R = np.array([[np.cos(a), -np.sin(a)], [np.sin(a), np.cos(a)]])
        out.append(mid + (P0 - mid) @ R.T * (1.0 + 0.3 * x))
    return out


def recheck(rest, F, uv, bound):
    """The frame checked outside the session: (certified, max distortion)."""
    V3 = np.column_stack([rest, np.zeros(len(rest))])
    corner = uv[F]
    D = bd_uv.conformal_distortion(V3, F, corner)
    flips = int(bd_uv.flipped_faces(V3, F, corner).sum())
    ov = bd_uv.island_overlaps(F, corner, np.zeros(len(F), dtype=np.int64), 1)
    return bool(flips == 0 and D.max() <= bound and ov.overlap_free[0]), float(D.max())


def blender_drag(V, F, rest, pins, targets):
    """Seconds of ``bpy.ops.uv.unwrap(method='CONFORMAL')`` per frame with the pins at each
    frame's targets (Blender's Live Unwrap re-solves LSCM with the pins every frame)."""
    from peers import _bpy_setup

    bpy = _bpy_setup()
    import bmesh                                  # importable once bpy is
    mesh = bpy.data.meshes.new("live")
    mesh.from_pydata(V.tolist(), [], F.tolist())
    mesh.update()
    obj = bpy.data.objects.new("live", mesh)
    bpy.context.scene.collection.objects.link(obj)
    seconds = []
    try:
        for other in bpy.context.scene.objects:
            other.select_set(other == obj)
        bpy.context.view_layer.objects.active = obj
        mesh.uv_layers.new(name="UVMap")
        bpy.ops.object.mode_set(mode="EDIT")
        bpy.ops.mesh.select_all(action="SELECT")
        bm = bmesh.from_edit_mesh(mesh)
        layer = bm.loops.layers.uv.active
        pin_loops = [[] for _ in pins]
        where = {int(v): i for i, v in enumerate(pins)}
        for face in bm.faces:                     # set-up only, untimed
            for loop in face.loops:
                loop[layer].uv = rest[loop.vert.index]
                i = where.get(loop.vert.index)
                if i is not None:
                    loop[layer].pin_uv = True
                    pin_loops[i].append(loop)
        for T in targets:
            for i, loops in enumerate(pin_loops):
                for loop in loops:
                    loop[layer].uv = T[i]
            t0 = time.perf_counter()
            bpy.ops.uv.unwrap(method="CONFORMAL", margin=0.0)
            seconds.append(time.perf_counter() - t0)
    finally:
        if bpy.context.object is not None and bpy.context.object.mode != "OBJECT":
            bpy.ops.object.mode_set(mode="OBJECT")
        bpy.data.objects.remove(obj)
        bpy.data.meshes.remove(mesh)
    return np.array(seconds)


def run(spec, frames, bound, blender):
    V, F = load_mesh_by_index(mesh_path(spec))
    load = os.getloadavg()[0]
    res = bd_uv.unwrap(V, F, bound=5.0, overlap="fail")
    if len(res.islands) != 1 or res.islands[0].status != "certified":
        return dict(mesh=spec, faces=len(F), note="no one certified overlap-free rest island")
    isl = res.islands[0]
    rest = np.zeros((len(V), 2))
    rest[isl.vertices] = isl.uv
    c, w = rest.mean(axis=0), np.ptp(rest, axis=0)
    pins = [int(np.argmin(np.linalg.norm(rest - p, axis=1)))
            for p in (c - [0.3 * w[0], 0.0], c + [0.3 * w[0], 0.0])]
    targets = drag(rest[pins], frames)
    t0 = time.perf_counter()
    s = bd_uv.LiveSession(V, F, pins, bound=bound, rest_uv=rest)
    setup = time.perf_counter() - t0
    lat, cpu, errs, cert, checked = [], [], [], 0, 0
    for T in targets:
        c0 = time.thread_time()
        fr = s.update(T)
        cpu.append(time.thread_time() - c0)
        lat.append(fr.seconds)
        errs.append(fr.pin_error)
        cert += fr.certified
        checked += recheck(rest, F, fr.uv, bound)[0]
    s.close()
    lat, cpu = 1000.0 * np.array(lat), 1000.0 * np.array(cpu)
    row = dict(mesh=spec, faces=len(F), load=load, setup=setup, median=np.median(lat),
               p95=np.percentile(lat, 95), max=lat.max(), cpu_median=np.median(cpu),
               cpu_p95=np.percentile(cpu, 95), pin_error=max(errs) / w.max(),
               certified=f"{cert}/{len(targets)}", checked=f"{checked}/{len(targets)}", note="")
    if blender:
        b = 1000.0 * blender_drag(V, F, rest, pins, targets)
        row.update(blender_median=np.median(b), blender_p95=np.percentile(b, 95),
                   ratio=np.median(b) / np.median(lat))
    return row


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("meshes", nargs="*", default=None)
    ap.add_argument("--frames", type=int, default=40)
    ap.add_argument("--bound", type=float, default=5.0)
    ap.add_argument("--no-blender", action="store_true")
    ap.add_argument("--big", action="store_true", help="add mannequin-devil subdivided once")
    args = ap.parse_args(argv)
    meshes = args.meshes or DEFAULT + (["mannequin-devil.off@sub1"] if args.big else [])
    print(f"drag of {args.frames} frames, C = {args.bound:g}, {os.cpu_count()} cores\n")
    head = ("| mesh | faces | load | set-up s | median ms | p95 ms | max ms | CPU median ms | "
            "CPU p95 ms | pin error | "
            "certified | re-checked |" + ("" if args.no_blender else
                                        " Blender median ms | Blender p95 ms | Blender / ours |"))
    print(head)
    print("|" + "---|" * (head.count("|") - 1))
    for spec in meshes:
        r = run(spec, args.frames, args.bound, not args.no_blender)
        if r.get("note"):
            print(f"| {r['mesh']} | {r['faces']} | {r['note']} |")
            continue
        line = (f"| {r['mesh']} | {r['faces']} | {r['load']:.1f} | {r['setup']:.2f} | "
                f"{r['median']:.1f} | {r['p95']:.1f} | {r['max']:.1f} | {r['cpu_median']:.1f} | "
                f"{r['cpu_p95']:.1f} | {r['pin_error']:.1e} | "
                f"{r['certified']} | {r['checked']} |")
        if not args.no_blender:
            line += f" {r['blender_median']:.1f} | {r['blender_p95']:.1f} | {r['ratio']:.2f}x |"
        print(line, flush=True)


if __name__ == "__main__":
    main()
