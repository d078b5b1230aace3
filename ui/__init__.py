"""Blender UI: menu entries and the UV editor sidebar panel; refers to operators by bl_idname."""
from . import menus, panel

classes = (*menus.classes, *panel.classes)


def register():
    panel.register()
    menus.register()


def unregister():
    menus.unregister()
    panel.unregister()
