"""Blender's primitives with every option at its default: ``uv.bd_unwrap`` against Blender's own
Smart UV Project and Unwrap, measured in the same run from the UVs as stored (float32).

    python3.11 benchmarks/first_contact.py

Needs the ``bpy`` module (``pip install bpy``). For each primitive (added fresh, all faces
selected in Edit Mode) and each unwrapper it prints the operator's result, the max and
area-weighted mean conformal distortion (numpy SVD of each triangle's map), flipped triangles, the
seams marked afterwards and the time, then per primitive the ratio of bd-uv's max distortion to
Smart UV Project's. Blender's Unwrap of a closed mesh without seams folds it onto itself: its
figures are printed, not compared.
"""
import importlib.util
import pathlib
import sys
import time

import numpy as np

import bpy

ROOT = pathlib.Path(__file__).resolve().parents[1]
PRIMITIVES = {
    "UV sphere": lambda: bpy.ops.mesh.primitive_uv_sphere_add(),
    "cube": lambda: bpy.ops.mesh.primitive_cube_add(),
    "torus": lambda: bpy.ops.mesh.primitive_torus_add(),
    "cylinder": lambda: bpy.ops.mesh.primitive_cylinder_add(),
    "cone": lambda: bpy.ops.mesh.primitive_cone_add(),
    "ico sphere": lambda: bpy.ops.mesh.primitive_ico_sphere_add(),
    "grid": lambda: bpy.ops.mesh.primitive_grid_add(),
    "Suzanne": lambda: bpy.ops.mesh.primitive_monkey_add(),
}
UNWRAPPERS = {
    "bd-uv": lambda: bpy.ops.uv.bd_unwrap(),
    "Smart UV": lambda: bpy.ops.uv.smart_project(),
    "Unwrap": lambda: bpy.ops.uv.unwrap(),
}


def load_addon():
    """The repository root imported as the add-on package (as Blender does)."""
    spec = importlib.util.spec_from_file_location(
        "bd_uv_addon", ROOT / "__init__.py", submodule_search_locations=[str(ROOT)])
    module = importlib.util.module_from_spec(spec)
    sys.modules["bd_uv_addon"] = module
    spec.loader.exec_module(module)
    return module


def stored_distortion(obj):
    """(max, area-weighted mean, flipped) from the stored UVs of every loop triangle."""
    mesh = obj.data
    mesh.calc_loop_triangles()
    n = len(mesh.loop_triangles)
    tris = np.empty(3 * n, np.int32)
    mesh.loop_triangles.foreach_get("vertices", tris)
    loops = np.empty(3 * n, np.int32)
    mesh.loop_triangles.foreach_get("loops", loops)
    co = np.empty(3 * len(mesh.vertices), np.float32)
    mesh.vertices.foreach_get("co", co)
    uv = np.empty(2 * len(mesh.loops), np.float32)
    mesh.uv_layers.active.uv.foreach_get("vector", uv)
    P = co.reshape(-1, 3).astype(np.float64)[tris.reshape(-1, 3)]
    T = uv.reshape(-1, 2).astype(np.float64)[loops.reshape(-1, 3)]
    e1, e2 = P[:, 1] - P[:, 0], P[:, 2] - P[:, 0]
    x = e1 / np.linalg.norm(e1, axis=1)[:, None]
    nrm = np.cross(e1, e2)
    area = 0.5 * np.linalg.norm(nrm, axis=1)
    y = np.cross(nrm / (2 * area)[:, None], x)
    S = np.stack([np.stack([(e1 * x).sum(1), (e1 * y).sum(1)], 1),
                  np.stack([(e2 * x).sum(1), (e2 * y).sum(1)], 1)], 2)
    J = np.stack([T[:, 1] - T[:, 0], T[:, 2] - T[:, 0]], 2) @ np.linalg.inv(S)
    s = np.linalg.svd(J, compute_uv=False)
    det = np.linalg.det(J)
    with np.errstate(divide="ignore", invalid="ignore"):
        D = np.where(det > 0, s[:, 0] / s[:, 1], np.inf)
    ok = np.isfinite(D)
    mean = float((D[ok] * area[ok]).sum() / area[ok].sum()) if ok.any() else float("nan")
    return float(D[ok].max()) if ok.any() else float("inf"), mean, int((det <= 0).sum())


def run(addon, name, unwrapper):
    bpy.ops.wm.read_factory_settings(use_empty=True)
    addon.register()
    try:
        PRIMITIVES[name]()
        obj = bpy.context.active_object
        bpy.ops.object.mode_set(mode='EDIT')
        bpy.ops.mesh.select_all(action='SELECT')
        t0 = time.perf_counter()
        result = UNWRAPPERS[unwrapper]()
        seconds = time.perf_counter() - t0
        bpy.ops.object.mode_set(mode='OBJECT')
        seams = np.empty(len(obj.data.edges), bool)
        obj.data.edges.foreach_get("use_seam", seams)
        return (next(iter(result)), *stored_distortion(obj), int(seams.sum()), seconds)
    finally:
        addon.unregister()


def main():
    addon = load_addon()
    print(f"{'primitive':<11} {'unwrapper':<9} {'result':<9} {'max D':>8} {'mean D':>7} "
          f"{'flipped':>7} {'seams':>6} {'seconds':>8}")
    ratios = []
    for name in PRIMITIVES:
        rows = {u: run(addon, name, u) for u in UNWRAPPERS}
        for u, (res, mx, mean, flips, seams, secs) in rows.items():
            print(f"{name:<11} {u:<9} {res:<9} {mx:8.3f} {mean:7.3f} {flips:7d} {seams:6d} "
                  f"{secs:8.3f}")
        ratio = rows["bd-uv"][1] / rows["Smart UV"][1]
        ratios.append(ratio)
        print(f"{name:<11} max distortion bd-uv / Smart UV Project: {ratio:.2f}")
    print(f"geometric mean of the ratios: {float(np.exp(np.mean(np.log(ratios)))):.2f}")


if __name__ == "__main__":
    main()
