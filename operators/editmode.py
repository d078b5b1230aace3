"""Leave Edit Mode around bulk mesh access, and come back with the same objects in Edit Mode."""
from contextlib import contextmanager

import bpy


def edit_mesh_objects(context):
    """The mesh objects in Edit Mode, one per mesh data-block (Blender's multi-object editing)."""
    objects = getattr(context, "objects_in_mode_unique_data", None) or []
    if not objects and context.edit_object is not None:
        objects = [context.edit_object]
    return [ob for ob in objects if ob.type == 'MESH']


@contextmanager
def object_mode(context):
    """Switch the objects in Edit Mode to Object Mode (syncing their meshes), then back.

    Yields the list of those objects. Everything in between sees (and may write) plain ``Mesh``
    data; on exit the edit-meshes are rebuilt from it.
    """
    objects = edit_mesh_objects(context)
    if not objects:
        yield []
        return
    names = [ob.name for ob in objects]
    bpy.ops.object.mode_set(mode='OBJECT')
    try:
        yield objects
    finally:
        # Objects may have been deleted meanwhile; re-enter Edit Mode with those still there.
        alive = [bpy.data.objects.get(n) for n in names]
        alive = [ob for ob in alive if ob is not None]
        if alive:
            view_layer = context.view_layer
            active = view_layer.objects.active
            if active is None or active.name not in names:
                view_layer.objects.active = alive[0]
            # mode_set(EDIT) takes every selected mesh along: leave other selected objects out.
            others = [ob for ob in context.selected_objects if ob.name not in names]
            for ob in others:
                ob.select_set(False)
            for ob in alive:
                ob.select_set(True)
            bpy.ops.object.mode_set(mode='EDIT')
            for ob in others:
                ob.select_set(True)
