"""Registration: everything the add-on adds is there after register() and gone after unregister()."""
import inspect

import numpy as np

from conftest import bpy, load_addon, load_submodule


CLASS_NAMES = ("UV_OT_bd_unwrap", "UV_OT_bd_show_distortion", "UV_OT_bd_select_distorted",
               "UV_OT_bd_deform", "UV_OT_bd_live", "MESH_OT_bd_improve",
               "IMAGE_PT_bd_uv_result", "BDUV_PG_last_result", "UV_OT_bd_pack")


def _footprint():
    """Everything of ours that Blender could still hold after unregister()."""
    names = {n for n in dir(bpy.types) if "bd_" in n.lower() or n.startswith("BDUV")}
    ours = (*load_submodule("operators").classes, *load_submodule("ui").classes,
            load_submodule("ui.panel").IMAGE_PT_bd_uv_result)
    names |= {cls.__name__ for cls in ours if cls.is_registered}
    ops = {n for n in dir(bpy.ops.uv) if n.startswith("bd_")} | {
        f"mesh.{n}" for n in dir(bpy.ops.mesh) if n.startswith("bd_")}
    props = {n for n in ("bd_uv_last_result",) if hasattr(bpy.types.WindowManager, n)}
    menus = {}
    for menu_name in ("IMAGE_MT_uvs_unwrap", "VIEW3D_MT_uv_map", "IMAGE_MT_uvs",
                      "VIEW3D_MT_edit_mesh_clean"):
        menu = getattr(bpy.types, menu_name, None)
        if menu is not None and hasattr(menu, "_dyn_ui_initialize"):
            menus[menu_name] = [f.__module__ for f in menu._dyn_ui_initialize()]
    return names, ops, props, menus


class FakeLayout:
    """Records what a draw function puts in a menu or panel (drawing needs a real window)."""

    def __init__(self):
        self.calls = []
        self.operator_context = None

    def operator(self, idname, **kwargs):
        self.calls.append(("operator", idname, kwargs.get("text")))

    def label(self, text="", **kwargs):
        self.calls.append(("label", text))

    def separator(self, **kwargs):
        pass

    def column(self, **kwargs):
        return self

    def box(self, **kwargs):
        return self

    def row(self, **kwargs):
        return self


def test_register_unregister_leaves_nothing_behind(empty_scene):
    addon = load_addon()
    before = _footprint()
    assert not before[1] and not before[2]
    for _ in range(2):  # twice: a second cycle must work as well as the first
        addon.register()
        names, ops, props, menus = _footprint()
        assert set(CLASS_NAMES) <= names
        assert ops == {"bd_unwrap", "bd_show_distortion", "bd_select_distorted", "bd_deform",
                       "bd_live", "mesh.bd_improve", "bd_pack"}
        assert props == {"bd_uv_last_result"}
        assert menus != before[3]
        addon.unregister()
        assert _footprint() == before


def test_menu_entry_is_in_uv_unwrap(addon):
    menus = load_submodule("ui.menus")
    unwrap_menu = getattr(bpy.types, "IMAGE_MT_uvs_unwrap", None) or bpy.types.VIEW3D_MT_uv_map
    assert menus.draw_unwrap_entry in unwrap_menu._dyn_ui_initialize()
    fake = type("Menu", (), {"layout": FakeLayout()})()
    menus.draw_unwrap_entry(fake, bpy.context)
    assert fake.layout.calls == [("operator", "uv.bd_unwrap", "Bounded Distortion")]
    assert fake.layout.operator_context == 'INVOKE_DEFAULT'  # the menu runs the background path
    # In 5.0 the 3D View's U menu shows it through IMAGE_MT_uvs_unwrap, so it is not added twice.
    assert menus.draw_unwrap_entry not in bpy.types.VIEW3D_MT_uv_map._dyn_ui_initialize()
    u_menu_draw = bpy.types.VIEW3D_MT_uv_map._dyn_ui_initialize()[0]  # Blender's own draw()
    assert 'menu_contents("IMAGE_MT_uvs_unwrap")' in inspect.getsource(u_menu_draw)


def test_panel_shows_the_last_result(addon):
    panel_cls = bpy.types.IMAGE_PT_bd_uv_result
    assert (panel_cls.bl_space_type, panel_cls.bl_region_type, panel_cls.bl_category) == (
        'IMAGE_EDITOR', 'UI', "BD-UV")
    last = bpy.context.window_manager.bd_uv_last_result
    last.valid, last.method, last.islands, last.failed = True, "BD-LSCM", 3, 1
    last.max_distortion, last.mean_distortion, last.bound_certified = 2.3125, 1.25, 5.0
    last.flipped, last.seconds = 0, 1.75
    fake = type("Panel", (), {"layout": FakeLayout()})()
    panel_cls.draw(fake, bpy.context)
    labels = [c[1] for c in fake.layout.calls if c[0] == "label"]
    assert labels == ["BD-LSCM: 3 islands, 1 failed", "Max distortion 2.312",
                      "Mean distortion 1.250", "Certified C 5", "Flipped 0", "Time 1.75 s"]
    ops = [c[1] for c in fake.layout.calls if c[0] == "operator"]
    assert ops == ["uv.bd_unwrap", "uv.bd_deform", "uv.bd_live", "uv.bd_show_distortion",
                   "uv.bd_select_distorted"]
    assert np.isclose(last.max_distortion, 2.3125)
