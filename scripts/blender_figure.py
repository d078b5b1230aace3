"""The README's "In Blender" picture, rendered headlessly with the ``bpy`` module.

    python3.11 scripts/blender_figure.py docs/images/in-blender.png

Blender's own primitives (UV sphere, cube, torus, cylinder), each unwrapped twice: by Blender's
Smart UV Project (top row) and by ``uv.bd_unwrap`` with every option at its default (bottom row),
then rendered by Cycles on the CPU with Blender's UV grid texture, so a square on the surface that
stays square is a conformal face. Each caption gives the max and mean conformal distortion of
the map as stored (recomputed from the float32 UVs by ``bd_uv.conformal_distortion``). Takes
about half a minute.
"""
import importlib.util
import os
import sys
import tempfile

import bpy
import numpy as np

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
PRIMITIVES = (
    ("UV sphere", lambda: bpy.ops.mesh.primitive_uv_sphere_add()),
    ("Cube", lambda: bpy.ops.mesh.primitive_cube_add(size=1.6)),
    ("Torus", lambda: bpy.ops.mesh.primitive_torus_add()),
    ("Cylinder", lambda: bpy.ops.mesh.primitive_cylinder_add(depth=1.6)),
)


def _addon():
    """The repository root imported as the add-on package (as Blender does), and registered."""
    spec = importlib.util.spec_from_file_location(
        "bd_uv_addon", os.path.join(ROOT, "__init__.py"), submodule_search_locations=[ROOT])
    module = importlib.util.module_from_spec(spec)
    sys.modules["bd_uv_addon"] = module
    spec.loader.exec_module(module)
    module.register()
    return module


def _grid_material():
    img = bpy.data.images.new("uv-grid", 1024, 1024)
    img.generated_type = 'UV_GRID'
    mat = bpy.data.materials.new("uv-grid")
    mat.use_nodes = True
    nodes = mat.node_tree.nodes
    tex = nodes.new("ShaderNodeTexImage")
    tex.image = img
    tex.interpolation = 'Closest'
    mat.node_tree.links.new(tex.outputs[0], nodes["Principled BSDF"].inputs["Base Color"])
    return mat


def _unwrap(kind):
    """Unwrap the active object's whole mesh with ``kind`` ('smart' or 'bd'); returns the
    operator's result set."""
    bpy.ops.object.mode_set(mode='EDIT')
    bpy.ops.mesh.select_all(action='SELECT')
    if kind == 'smart':
        result = bpy.ops.uv.smart_project()
    else:
        result = bpy.ops.uv.bd_unwrap()
    bpy.ops.object.mode_set(mode='OBJECT')
    return result


def _stored_measure(addon, ob):
    """(max, mean) conformal distortion of the UVs as stored (area-weighted mean)."""
    mesh_data = importlib.import_module("bd_uv_addon.operators.mesh_data")
    arrays = mesh_data.mesh_arrays(ob)
    D = addon.bd_uv.conformal_distortion(arrays.V, arrays.F, arrays.corner_uv)
    area = np.linalg.norm(np.cross(arrays.V[arrays.F[:, 1]] - arrays.V[arrays.F[:, 0]],
                                   arrays.V[arrays.F[:, 2]] - arrays.V[arrays.F[:, 0]]), axis=1)
    mean = float(np.sum(D * area) / np.sum(area)) if np.all(np.isfinite(D)) else float("inf")
    return float(np.max(D)), mean


def _render(ob, path):
    scene = bpy.context.scene
    for other in scene.objects:
        other.hide_render = other.type == 'MESH' and other is not ob
    scene.render.filepath = path
    bpy.ops.render.render(write_still=True)


def _setup_scene():
    bpy.ops.wm.read_factory_settings(use_empty=True)
    scene = bpy.context.scene
    cam = bpy.data.objects.new("camera", bpy.data.cameras.new("camera"))
    scene.collection.objects.link(cam)
    scene.camera = cam
    cam.location = (0.0, -4.2, 2.6)
    cam.rotation_euler = (1.0, 0.0, 0.0)
    sun = bpy.data.objects.new("sun", bpy.data.lights.new("sun", 'SUN'))
    sun.data.energy = 3.0
    sun.rotation_euler = (0.7, 0.2, 0.4)
    scene.collection.objects.link(sun)
    scene.world = bpy.data.worlds.new("world")
    scene.world.color = (0.35, 0.35, 0.35)
    scene.render.engine = 'CYCLES'
    scene.cycles.device = 'CPU'
    scene.cycles.samples = 24
    scene.render.resolution_x = scene.render.resolution_y = 360
    scene.render.film_transparent = False
    return scene


def main(out):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.image as mpimg
    import matplotlib.pyplot as plt

    addon = _addon()
    _setup_scene()
    mat = _grid_material()
    tmp = tempfile.mkdtemp(prefix="bd-uv-figure-")
    rows = {"smart": [], "bd": []}
    for name, add in PRIMITIVES:
        for kind in rows:
            for ob in list(bpy.data.objects):
                if ob.type == 'MESH':
                    bpy.data.objects.remove(ob)
            add()
            ob = bpy.context.object
            ob.data.materials.append(mat)
            bpy.ops.object.shade_smooth()
            result = _unwrap(kind)
            worst, mean = _stored_measure(addon, ob)
            path = os.path.join(tmp, f"{kind}-{name}.png")
            _render(ob, path)
            rows[kind].append((name, path, result, worst, mean))
    addon.unregister()

    fig, axes = plt.subplots(2, len(PRIMITIVES), figsize=(3 * len(PRIMITIVES), 6.9))
    titles = {"smart": "Smart UV Project", "bd": "bd-uv, one click (defaults)"}
    for r, kind in enumerate(rows):
        for c, (name, path, result, worst, mean) in enumerate(rows[kind]):
            ax = axes[r, c]
            ax.imshow(mpimg.imread(path))
            ax.set_xticks([])
            ax.set_yticks([])
            status = "" if result == {'FINISHED'} else f" ({', '.join(sorted(result))})"
            ax.set_title(f"{name}{status}\nmax distortion {worst:.2f}, mean {mean:.3f}",
                         fontsize=10)
            if c == 0:
                ax.set_ylabel(titles[kind], fontsize=11)
    fig.tight_layout()
    os.makedirs(os.path.dirname(os.path.abspath(out)), exist_ok=True)
    fig.savefig(out, dpi=100)
    print(f"wrote {out}")
    for kind in rows:
        for name, _, result, worst, mean in rows[kind]:
            print(f"{titles[kind]:30s} {name:10s} {sorted(result)} max {worst:.3f} mean {mean:.4f}")


if __name__ == "__main__":
    args = [a for a in sys.argv[1:] if not a.startswith("-")]
    main(args[0] if args else os.path.join(ROOT, "docs", "images", "in-blender.png"))
