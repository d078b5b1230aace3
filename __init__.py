"""bd-uv: Bounded Distortion UV unwrapping (Lipman 2012) as a Blender extension.

The repo root is the extension root; Blender imports it as a package (``bl_ext.<repo>.bd_uv``).
``bpy`` and the Blender-side subpackages are imported inside ``register()`` only, so the core
(``bd_uv/``) and the tests can import this package without Blender.
"""


def register():
    from . import operators, ui

    operators.register()
    ui.register()


def unregister():
    from . import operators, ui

    ui.unregister()
    operators.unregister()
