"""Blender operators over the ``bd_uv`` core.

``mesh_data`` is the only module converting between ``bpy`` and numpy; ``worker`` runs the
solve in a background thread without ``bpy``; ``session`` is one unwrap (gather, write back,
pack, report) shared by the operator's synchronous and background paths; ``background`` is
those two paths for the deform and improve operators, whose bpy-free work is in ``uv_deform``
and ``planar``.
"""
import bpy

from . import deform, display, improve, live, pack, properties, unwrap

classes = (*properties.classes, *unwrap.classes, *display.classes, *deform.classes,
           *improve.classes, *live.classes, *pack.classes)


def register():
    for cls in classes:
        bpy.utils.register_class(cls)
    properties.register()


def unregister():
    properties.unregister()
    for cls in reversed(classes):
        bpy.utils.unregister_class(cls)
