"""Scene files end to end: real meshes put into glTF and USD scenes by Blender's own exporters,
unwrapped whole by ``python -m bd_uv unwrap``, and checked from the files written.

For each mesh: Blender (the ``bpy`` module) builds a scene holding it (smooth shaded, so the
exporters split vertices only where UVs differ), exports it as ``.glb`` and ``.usdc``, and the
same mesh is also written as an OBJ. Each file goes through ``python -m bd_uv unwrap --seams auto
--bound C`` in a child process. The outputs are read back here, without bd_uv (pygltflib-free
JSON + numpy for glTF, pxr for USD), and certified independently: per triangle the distortion from
numpy's SVD of the map from the 3D triangle to its UVs, flips from signed areas, overlaps with the
exact separating-axis test of ``tests/core/overlap_shapes.py``. Times are ratios to the OBJ run of
the same mesh in the same run (a shared machine: read them as rough).

    python3.11 benchmarks/bench_scenes.py [--bound 2] MESH...    (default: three shared meshes)
"""
import argparse
import json
import os
import struct
import subprocess
import sys
import tempfile
import time

import numpy as np

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, os.path.join(ROOT, "tests", "core"))
from helpers import reference_distortion  # noqa: E402
from overlap_shapes import overlapping_triangle_pairs  # noqa: E402

DEFAULT = ["/work/shared/meshes/cow.off", "/work/shared/meshes/suzanne.obj",
           "/work/shared/meshes/fandisk.off"]


def export_scenes(mesh_path, folder):
    """glb, usdc and obj of one mesh, written by Blender's exporters (bpy)."""
    import bpy
    import trimesh
    m = trimesh.load(mesh_path, process=False, force="mesh")
    bpy.ops.wm.read_factory_settings(use_empty=True)
    me = bpy.data.meshes.new("Body")
    me.from_pydata(np.asarray(m.vertices).tolist(), [], np.asarray(m.faces).tolist())
    me.shade_smooth()
    ob = bpy.data.objects.new("Prop", me)
    bpy.context.scene.collection.objects.link(ob)
    stem = os.path.join(folder, os.path.splitext(os.path.basename(mesh_path))[0])
    bpy.ops.export_scene.gltf(filepath=stem + ".glb", export_format="GLB")
    bpy.ops.wm.usd_export(filepath=stem + ".usdc")
    bpy.ops.wm.obj_export(filepath=stem + ".obj", export_materials=False, export_uv=False,
                          export_normals=False)
    return {"glb": stem + ".glb", "usdc": stem + ".usdc", "obj": stem + ".obj"}


def glb_corners(path, uv_set=0):
    """(positions (m,3,3), uvs (m,3,2) with v upwards) per triangle corner of every mesh."""
    raw = open(path, "rb").read()
    n = struct.unpack_from("<I", raw, 12)[0]
    doc = json.loads(raw[20:20 + n])
    blob = raw[20 + n + 8:]
    dt = {5123: "<u2", 5125: "<u4", 5126: "<f4", 5121: "<u1"}
    width = {"SCALAR": 1, "VEC2": 2, "VEC3": 3}

    def acc(i):
        a = doc["accessors"][i]
        v = doc["bufferViews"][a["bufferView"]]
        w, d = width[a["type"]], np.dtype(dt[a["componentType"]])
        stride = v.get("byteStride", w * d.itemsize)
        start = v.get("byteOffset", 0) + a.get("byteOffset", 0)
        return np.array([np.frombuffer(blob, d, w, start + r * stride)
                         for r in range(a["count"])])

    P, U = [], []
    for mesh in doc["meshes"]:
        for p in mesh["primitives"]:
            idx = acc(p["indices"])[:, 0]
            P.append(acc(p["attributes"]["POSITION"])[idx].reshape(-1, 3, 3))
            uv = acc(p["attributes"][f"TEXCOORD_{uv_set}"])[idx].astype(float)
            U.append(np.stack([uv[:, 0], 1 - uv[:, 1]], 1).reshape(-1, 3, 2))
    return np.concatenate(P).astype(float), np.concatenate(U)


def usd_corners(path):
    from pxr import Usd, UsdGeom
    P, U = [], []
    stage = Usd.Stage.Open(path)
    for prim in stage.Traverse():
        if not prim.IsA(UsdGeom.Mesh):
            continue
        m = UsdGeom.Mesh(prim)
        pv = UsdGeom.PrimvarsAPI(prim).GetPrimvar("st")
        uv = np.asarray(pv.Get(), float)[np.asarray(pv.GetIndices())]
        pts = np.asarray(m.GetPointsAttr().Get(), float)
        idx = np.asarray(m.GetFaceVertexIndicesAttr().Get())
        T, s = [], 0
        for c in m.GetFaceVertexCountsAttr().Get():
            T += [(s, s + i, s + i + 1) for i in range(1, c - 1)]
            s += c
        T = np.array(T)
        P.append(pts[idx[T]])
        U.append(uv[T])
    return np.concatenate(P), np.concatenate(U)


def obj_corners(path):
    V, VT, F, FT = [], [], [], []
    for line in open(path):
        t = line.split()
        if not t:
            continue
        if t[0] == "v":
            V.append([float(x) for x in t[1:4]])
        elif t[0] == "vt":
            VT.append([float(x) for x in t[1:3]])
        elif t[0] == "f":
            F.append([int(x.split("/")[0]) - 1 for x in t[1:4]])
            FT.append([int(x.split("/")[1]) - 1 for x in t[1:4]])
    return np.array(V)[np.array(F)], np.array(VT)[np.array(FT)]


def check(P, U, bound):
    V = P.reshape(-1, 3)
    F = np.arange(len(V)).reshape(-1, 3)
    D, flipped = reference_distortion(V, F, U)
    return {"faces": len(F), "max": float(D.max()), "flips": int(flipped.sum()),
            "overlaps": int(len(overlapping_triangle_pairs(U))),
            "ok": bool(D.max() <= bound * (1 + 1e-9) and not flipped.any())}


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("meshes", nargs="*", default=DEFAULT)
    ap.add_argument("--bound", type=float, default=2.0)
    args = ap.parse_args()
    readers = {"glb": glb_corners, "usdc": usd_corners, "obj": obj_corners}
    print(f"{'mesh':<14} {'format':<5} {'faces':>6} {'max D':>7} {'C':>4} {'flips':>5} "
          f"{'overlaps':>8} {'s':>6} {'x OBJ':>6}")
    with tempfile.TemporaryDirectory() as tmp:
        for mesh in args.meshes:
            files = export_scenes(mesh, tmp)
            secs = {}
            for fmt in ("obj", "glb", "usdc"):
                out = os.path.join(tmp, "out", os.path.basename(files[fmt]))
                t0 = time.perf_counter()
                proc = subprocess.run([sys.executable, "-m", "bd_uv", "unwrap", files[fmt], "-o",
                                       out, "--seams", "auto", "--bound", str(args.bound)],
                                      cwd=ROOT, capture_output=True, text=True)
                secs[fmt] = time.perf_counter() - t0
                if proc.returncode != 0:
                    print(f"{os.path.basename(mesh):<14} {fmt:<5} FAILED: {proc.stderr[-300:]}")
                    continue
                r = check(*readers[fmt](out), args.bound)
                print(f"{os.path.basename(mesh):<14} {fmt:<5} {r['faces']:>6} {r['max']:>7.4f} "
                      f"{args.bound:>4g} {r['flips']:>5} {r['overlaps']:>8} {secs[fmt]:>6.1f} "
                      f"{secs[fmt] / secs['obj']:>6.2f}")


if __name__ == "__main__":
    main()
