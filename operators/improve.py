"""``mesh.bd_improve``: make a flat selection's triangles as close to equilateral as bd-uv can
certify (Lipman 2012, section 6.6), moving interior vertices within the plane only.

Per mesh in Edit Mode, the selected faces must be triangles (quads and n-gons are refused: their
triangulation is Blender's choice and a quad made of two near-equilateral triangles is a rhombus;
Face > Triangulate Faces first) lying in one plane within the Flatness tolerance. Vertices on the
selection's boundary stay bit for bit; the others move within the plane
(``operators/planar.py``); a selection with a vertex inside it that an unselected face uses too
is refused. What is stored is checked again: boundary unchanged, no face turned over and no face
with an interior vertex further from equilateral than the worst one was before; otherwise the
positions are put back. The report gives the max distortion against the equilateral before and
after. One undo step.
"""
from dataclasses import dataclass

import numpy as np

import bpy
from bpy.props import FloatProperty

from . import mesh_data, planar
from .background import BackgroundSolve
from .editmode import edit_mesh_objects, object_mode
from .report import _down, _up


@dataclass(frozen=True)
class _Selection:
    """One object's flat selection as gathered (Object Mode)."""

    object_name: str
    arrays: object        # mesh_data.MeshArrays of the selected triangles (scale applied)
    scale: np.ndarray     # (3,) object scale the positions were multiplied by
    co: np.ndarray        # (n,3) float32 positions of every vertex before


class MESH_OT_bd_improve(BackgroundSolve, bpy.types.Operator):
    """Move the interior vertices of the selected flat triangles within their plane so every
    triangle is as close to equilateral as can be certified (boundary vertices unchanged)"""

    bl_idname = "mesh.bd_improve"
    bl_label = "Improve Triangles (Bounded Distortion)"
    bl_options = {'REGISTER', 'UNDO'}
    JOB = "Bounded Distortion mesh improvement"

    tolerance: FloatProperty(name="Flatness", default=1e-5, min=0.0, max=0.1, precision=6,
                             description="Largest distance of a selected vertex from the "
                             "selection's plane, relative to its size")

    @classmethod
    def poll(cls, context):
        if edit_mesh_objects(context):
            return True
        cls.poll_message_set("Needs a mesh in Edit Mode with flat triangles selected")
        return False

    def _prepare(self, context):
        selections, problems = [], []
        with object_mode(context) as objects:
            for ob in objects:
                scale = np.array(ob.scale, dtype=np.float64)
                if not (np.isfinite(scale).all() and (scale != 0).all()):
                    self.report({'WARNING'}, f"{ob.name} has a zero scale: nothing to improve")
                    return None
                arrays = mesh_data.mesh_arrays(ob, selected_only=True, scale=scale)
                if not len(arrays.F):
                    continue
                mesh = ob.data
                sizes = mesh_data.polygon_sizes(mesh)
                polys = np.unique(arrays.tri_poly)
                not_tri = polys[sizes[polys] != 3]
                if len(not_tri):
                    self.report({'WARNING'}, f"{ob.name}: {len(not_tri)} selected faces are not "
                                f"triangles (faces {_some(not_tri)}); triangulate them first "
                                "(Face > Triangulate Faces)")
                    return None
                others = np.ones(len(mesh.polygons), dtype=bool)
                others[polys] = False
                shared = mesh_data.vertices_of_polygons(mesh, others)[arrays.vertices]
                touching = _inside(arrays.F, np.flatnonzero(shared))
                if len(touching):  # moving them would move unselected faces
                    self.report({'WARNING'}, f"{ob.name}: {len(touching)} vertices inside the "
                                "selection are used by unselected faces too (vertices "
                                f"{_some(arrays.vertices[touching])}); select those faces as "
                                "well or leave the vertices out")
                    return None
                selections.append(_Selection(ob.name, arrays, scale,
                                             mesh_data.vertex_positions(mesh)))
                problems.append((arrays.V, arrays.F))
        if not selections:
            self.report({'WARNING'}, "No faces selected: select the flat triangles to improve")
            return None
        return selections, planar.improve_many, (problems,), dict(tolerance=self.tolerance)

    def _finish(self, context, selections, results, seconds):
        lines, wrote, level = [], False, 'INFO'
        with object_mode(context):
            for sel, res in zip(selections, results):
                if isinstance(res, Exception):
                    lines.append(f"{sel.object_name}: {res}")
                    level = 'WARNING'
                    continue
                text, ok = _write_and_check(sel, res)
                lines.append(text)
                wrote |= ok
                if not ok:
                    level = 'WARNING'
        message = "; ".join(lines) + f"; {seconds:.1f} s"
        self.report({level}, message)
        context.window_manager.bd_uv_last_result.report = message
        return {'FINISHED'} if wrote else {'CANCELLED'}


def _some(values, k=8):
    values = [int(v) for v in values]
    return ", ".join(map(str, values[:k])) + (f", ... ({len(values)} in all)"
                                               if len(values) > k else "")


def _inside(F, vertices):
    """The (k,) ``vertices`` not on the boundary of the triangles (m,3) ``F``."""
    E = np.sort(np.concatenate([F[:, [0, 1]], F[:, [1, 2]], F[:, [2, 0]]]), axis=1)
    _, inv, cnt = np.unique(E, axis=0, return_inverse=True, return_counts=True)
    return np.setdiff1d(vertices, E[cnt[inv.ravel()] == 1])


def _write_and_check(sel, improved):
    """Write the moved vertices of one object, check what is stored, put it back if it fails
    (Object Mode).

    Returns
    -------
    text : str, the object's report; ok : bool, something was written and kept
    """
    ob = bpy.data.objects.get(sel.object_name)
    a = sel.arrays
    res = improved.result
    name = sel.object_name
    if ob is None or mesh_data.mesh_arrays(ob, selected_only=True,
                                           scale=sel.scale).topology_key != a.topology_key:
        return f"{name} not written: changed while solving", False
    before = f"max distortion against the equilateral {_down(res.max_before)}"
    if not len(improved.interior):
        return (f"{name}: {before}, nothing better found" if res.solves
                else f"{name}: {before}; no interior vertex to move"), False
    ids = a.vertices[improved.interior]
    mesh_data.set_vertex_positions(ob.data, ids, improved.positions / sel.scale)
    now = mesh_data.vertex_positions(ob.data)
    D, area = planar.stored_distortion(now.astype(np.float64)[a.vertices] * sel.scale, a.F,
                                       improved.plane)
    boundary_kept = np.array_equal(np.delete(now, ids, axis=0), np.delete(sel.co, ids, axis=0))
    movable = np.isin(a.F, improved.interior).any(axis=1)
    worst = res.distortion_before[movable].max()
    # Kept when nothing turned over and no face is further from equilateral than the worst was.
    ok = boundary_kept and bool((area > 0).all()) and D[movable].max() <= worst
    if not ok:
        mesh_data.set_vertex_positions(ob.data, ids, sel.co[ids])
        return (f"{name} put back as it was: the stored positions fail the check "
                f"({int((area <= 0).sum())} turned over, max distortion {D[movable].max():.4g} "
                f"against {worst:.4g} before)"), False
    lower = 100.0 * (1.0 - D.max() / res.max_before)
    # As the command line says it: a face with all three corners on the boundary cannot change.
    held = "" if D[movable].max() == D.max() else (
        f" (faces with an interior vertex {_down(worst)} \u2192 {_up(D[movable].max())}; the "
        "max is a face with all corners on the boundary)")
    return (f"{name}: {before} \u2192 {_up(D.max())} ({lower:.0f}% lower){held}, {len(ids)} "
            "interior vertices moved within the plane, boundary unchanged, 0 flipped"), True


classes = (MESH_OT_bd_improve,)
