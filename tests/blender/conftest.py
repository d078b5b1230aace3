"""Fixtures for tests that run the add-on through the ``bpy`` module (headless Blender).

Blender imports the repo root as a package (``bl_ext.<repo>.bd_uv``). Here the root is loaded the
same way, under the fixed name ``bd_uv_addon``, whatever the checkout folder is called, so the
add-on's relative imports (``from .. import bd_uv``) resolve exactly as they do in Blender.
"""
import importlib.util
import pathlib
import sys

import numpy as np
import pytest

bpy = pytest.importorskip("bpy")

REPO_ROOT = pathlib.Path(__file__).resolve().parents[2]
ADDON_NAME = "bd_uv_addon"


def load_addon():
    """The repo root imported as the package ``bd_uv_addon`` (cached in ``sys.modules``)."""
    if ADDON_NAME in sys.modules:
        return sys.modules[ADDON_NAME]
    spec = importlib.util.spec_from_file_location(
        ADDON_NAME, REPO_ROOT / "__init__.py", submodule_search_locations=[str(REPO_ROOT)])
    module = importlib.util.module_from_spec(spec)
    sys.modules[ADDON_NAME] = module
    spec.loader.exec_module(module)
    return module


def load_submodule(name):
    """``bd_uv_addon.<name>``, e.g. ``load_submodule("operators.mesh_data")``."""
    load_addon()
    return importlib.import_module(f"{ADDON_NAME}.{name}")


@pytest.fixture
def empty_scene():
    """A factory-fresh, empty scene in Object Mode."""
    bpy.ops.wm.read_factory_settings(use_empty=True)
    yield bpy.context.scene
    if bpy.context.object is not None and bpy.context.object.mode != 'OBJECT':
        bpy.ops.object.mode_set(mode='OBJECT')


@pytest.fixture
def addon(empty_scene):
    """The add-on registered for the duration of one test."""
    module = load_addon()
    module.register()
    try:
        yield module
    finally:
        module.unregister()


@pytest.fixture
def mesh_data():
    return load_submodule("operators.mesh_data")


def set_mode(obj, mode):
    """Make ``obj`` the only selected, active object and put it in ``mode``."""
    view_layer = bpy.context.view_layer
    if bpy.context.object is not None and bpy.context.object.mode != 'OBJECT':
        bpy.ops.object.mode_set(mode='OBJECT')
    for other in view_layer.objects:
        other.select_set(False)
    view_layer.objects.active = obj
    obj.select_set(True)
    if mode != 'OBJECT':
        bpy.ops.object.mode_set(mode=mode)


def select_polygons(obj, mask):
    """Select exactly the polygons in the (P,) bool ``mask`` (and their vertices and edges).

    Leaves ``obj`` in Object Mode.
    """
    set_mode(obj, 'OBJECT')
    mesh = obj.data
    mask = np.asarray(mask, dtype=bool)
    mesh.polygons.foreach_set("select", mask)
    loop_start = np.empty(len(mesh.polygons), np.int32)
    mesh.polygons.foreach_get("loop_start", loop_start)
    loop_total = np.empty(len(mesh.polygons), np.int32)
    mesh.polygons.foreach_get("loop_total", loop_total)
    loop_vert = np.empty(len(mesh.loops), np.int32)
    mesh.loops.foreach_get("vertex_index", loop_vert)
    loop_edge = np.empty(len(mesh.loops), np.int32)
    mesh.loops.foreach_get("edge_index", loop_edge)
    loop_sel = np.repeat(mask, loop_total)
    vsel = np.zeros(len(mesh.vertices), bool)
    vsel[loop_vert[loop_sel]] = True
    esel = np.zeros(len(mesh.edges), bool)
    esel[loop_edge[loop_sel]] = True
    mesh.vertices.foreach_set("select", vsel)
    mesh.edges.foreach_set("select", esel)
    mesh.update()


def loop_uv_array(mesh, name=None):
    """(L,2) float32 UVs of every loop of ``mesh`` (Object Mode)."""
    layer = mesh.uv_layers[name] if name else mesh.uv_layers.active
    out = np.empty(len(mesh.loops) * 2, np.float32)
    layer.uv.foreach_get("vector", out)
    return out.reshape(-1, 2)


def add_suzanne_with_seams():
    """Suzanne, with seams cut by Smart UV Project so every island is a disk; UVs reset.

    Returns the object in Object Mode, all faces selected.
    """
    bpy.ops.mesh.primitive_monkey_add()
    obj = bpy.context.active_object
    bpy.ops.object.mode_set(mode='EDIT')
    bpy.ops.mesh.select_all(action='SELECT')
    bpy.ops.uv.smart_project()
    bpy.ops.uv.seams_from_islands()
    bpy.ops.uv.reset()
    bpy.ops.object.mode_set(mode='OBJECT')
    return obj


def add_grid(x=6, y=5, size=2.0):
    """An open, flat-ish grid (a disk) with a UV map; Object Mode, all faces selected."""
    bpy.ops.mesh.primitive_grid_add(x_subdivisions=x, y_subdivisions=y, size=size)
    obj = bpy.context.active_object
    set_mode(obj, 'OBJECT')
    # Bend it so the unwrap has something to do.
    co = np.empty(len(obj.data.vertices) * 3, np.float32)
    obj.data.vertices.foreach_get("co", co)
    co = co.reshape(-1, 3)
    co[:, 2] = 0.3 * np.sin(1.7 * co[:, 0]) * np.cos(1.3 * co[:, 1])
    obj.data.vertices.foreach_set("co", co.ravel())
    obj.data.update()
    return obj


def triangle_distortion(V, tris, uv):
    """Conformal distortion and signed UV area of each triangle, from first principles.

    Independent of ``bd_uv``: each triangle is laid out isometrically in 2D, the 2x2 Jacobian ``J``
    of the affine map to its UVs is formed, and its singular values come from ``numpy.linalg.svd``.

    Parameters
    ----------
    V : (n,3) float, tris : (m,3) int, uv : (m,3,2) float (per-corner UVs)

    Returns
    -------
    distortion : (m,) float (sigma_max / sigma_min; inf when det J <= 0)
    det : (m,) float (det J: positive for an orientation-preserving face)
    """
    P = np.asarray(V, np.float64)[np.asarray(tris)]
    e1 = P[:, 1] - P[:, 0]
    e2 = P[:, 2] - P[:, 0]
    l1 = np.linalg.norm(e1, axis=1)
    x_axis = e1 / l1[:, None]
    n = np.cross(e1, e2)
    y_axis = np.cross(n / np.linalg.norm(n, axis=1)[:, None], x_axis)
    # 2D isometric layout: p0 = 0, p1 = (l1, 0), p2 = (e2.x, e2.y)
    X = np.stack([np.stack([l1, np.zeros_like(l1)], 1),
                  np.stack([(e2 * x_axis).sum(1), (e2 * y_axis).sum(1)], 1)], axis=2)  # (m,2,2)
    uv = np.asarray(uv, np.float64)
    U = np.stack([uv[:, 1] - uv[:, 0], uv[:, 2] - uv[:, 0]], axis=2)  # (m,2,2)
    J = U @ np.linalg.inv(X)
    s = np.linalg.svd(J, compute_uv=False)
    det = np.linalg.det(J)
    with np.errstate(divide="ignore", invalid="ignore"):
        D = np.where(det > 0, s[:, 0] / s[:, 1], np.inf)
    return D, det
