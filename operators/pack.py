"""``uv.bd_pack`` (UV > Pack Islands (Bounded Distortion)): the atlas packer on selected islands.

Any UV islands, bd-uv's or not, of the selected faces of every mesh in Edit Mode are packed
together into one square (or UDIM tiles) by ``bd_uv.packing.pack_islands``: turns only, the
padding in texels, one texel density; islands holding a pinned UV stay where they are and the
others are packed into the free space around them; optionally the islands of one material (the
faces' material slots) or of one object packed together. The UVs are written as float32 and the layout certificate
is measured on them as written; the status bar gets its figures. One undo step. ``pack_atlas``
is also what ``uv.bd_unwrap`` packs with by default.
"""
import time

import bpy
import numpy as np
from bpy.props import BoolProperty, EnumProperty, FloatProperty, IntProperty

from ..bd_uv.errors import BDError, PackError
from ..bd_uv.packing import PackOptions, layout_certificate, pack_islands, uv_islands
from . import mesh_data
from .editmode import edit_mesh_objects, object_mode

ROTATE_ITEMS = (('any', "Any Angle", "Turn charts by any angle (never mirrored)"),
                ('90', "Quarter Turns", "Turn charts by multiples of 90 degrees"),
                ('none', "None", "Keep every chart's orientation"))
GROUP_ITEMS = (('none', "None", "Pack every island freely"),
               ('material', "Material", "Pack the islands of one material together: one block "
                "per material, blocks apart by the padding"),
               ('object', "Object", "Pack the islands of one object together (several objects "
                "in Edit Mode): one block per object"))


def face_labels(ob, arrays, keep, number, materials):
    """Each kept triangle's material (numbered across objects by ``materials``, a dict material
    name -> number: the same material in two objects is one group; an empty slot is one too) and
    object (``number``)."""
    index, names = mesh_data.polygon_materials(ob)
    ids = np.array([materials.setdefault(n, len(materials)) for n in names], dtype=np.int64)
    return ids[index[arrays.tri_poly[keep]]], np.full(int(keep.sum()), number, dtype=np.int64)


def pack_atlas(objects, polygons, options):
    """Pack the UV islands of the given polygons of several objects together (Object Mode).

    Parameters
    ----------
    objects : list of bpy.types.Object (meshes, not in Edit Mode)
    polygons : list of (P_i,) bool, the polygons to pack of each object
    options : bd_uv.packing.PackOptions (``group``: islands of one material, from the faces'
        material slots, or of one object packed together)

    Returns
    -------
    (Packed, LayoutCertificate, islands) or None when nothing was to pack. Islands holding a
    pinned UV stay where they are (they must lie in the unit square) and the others are packed
    beside them. Raises ``BDError`` (nothing written) when the islands cannot be packed: flipped
    faces, a pinned island outside the square, or a layout that fails its certificate.
    """
    parts, Vs, Fs, uvs, labs, pins, nv, nl = [], [], [], [], [], [], 0, 0
    mats, obs, materials = [], [], {}
    for number, (ob, mask) in enumerate(zip(objects, polygons)):
        if not mask.any():
            continue
        arrays = mesh_data.mesh_arrays(ob, scale=tuple(ob.scale))
        keep = mask[arrays.tri_poly]
        if arrays.corner_uv is None or not keep.any():
            continue
        corner_pins = np.zeros(len(arrays.F) * 3, dtype=bool)
        corner_pins[arrays.pin_corners] = True
        pin_face = corner_pins.reshape(-1, 3)[keep].any(axis=1)
        lab = uv_islands(arrays.F[keep], arrays.corner_uv[keep])
        has = lab >= 0
        pins.append(np.bincount(lab[has], weights=pin_face[has], minlength=int(lab.max()) + 1) > 0)
        parts.append((ob, arrays, keep))
        Vs.append(arrays.V)
        Fs.append(arrays.F[keep] + nv)
        uvs.append(arrays.corner_uv[keep])
        labs.append(np.where(lab >= 0, lab + nl, -1))
        mat, obj = face_labels(ob, arrays, keep, number, materials)
        mats.append(mat)
        obs.append(obj)
        nv += len(arrays.V)
        nl += int(lab.max()) + 1
    if not parts:
        return None
    V, F, uv, lab = map(np.concatenate, (Vs, Fs, uvs, labs))
    pinned = np.concatenate(pins)
    labels = {"material": np.concatenate(mats), "object": np.concatenate(obs)}
    packed = pack_islands(V, F, uv, lab, options, pinned=pinned if pinned.any() else None,
                          face_labels=labels)
    stored = packed.corner_uv.astype(np.float32)
    cert = layout_certificate(V, F, stored, lab, packed.tile, options.resolution,
                                            options.padding_px)
    if not cert.certified:
        raise PackError(f"the packed layout fails its certificate: {cert.reason}; "
                                     "nothing was written")
    start = 0
    for ob, arrays, keep in parts:
        n = int(keep.sum())
        out = np.full(arrays.corner_uv.shape, np.nan)
        out[keep] = stored[start:start + n]
        mesh_data.write_corner_uvs(ob.data, arrays.uv_name, arrays.tri_loops, out, keep)
        start += n
    return packed, cert, nl


def pack_message(packed, cert, islands, head=None):
    """The status-bar line of a packing (``head``: its start, "Packed N islands: " by default)."""
    gap = "" if not np.isfinite(cert.least_gap_px) else f", least gap {cert.least_gap_px:.2f} px"
    tiles = ", ".join(map(str, cert.tiles))
    if head is None:
        head = f"Packed {islands} island{'s' if islands != 1 else ''}: "
    return (f"{head}coverage {cert.coverage:.3f} "
            f"at {cert.resolution} px{gap} (padding {cert.padding_px:g} px), tile"
            f"{'s' if len(cert.tiles) > 1 else ''} {tiles}, {packed.texel_density:.4g} texels per "
            f"unit, {packed.seconds:.2f} s")


class UV_OT_bd_pack(bpy.types.Operator):
    """Pack the selected UV islands by their true shapes (turns only), with padding in texels,
    one texel density and optional UDIM tiles; the layout is certified as written"""
    bl_idname = "uv.bd_pack"
    bl_label = "Pack Islands (Bounded Distortion)"
    bl_options = {'REGISTER', 'UNDO'}

    resolution: IntProperty(name="Resolution", default=1024, min=8, max=65536,
                            description="Texture size in texels the padding is measured at")
    padding: FloatProperty(name="Padding", default=4.0, min=0.0, soft_max=32.0,
                           description="Least gap between islands in texels (half of it to the "
                           "edge)")
    use_texel_density: BoolProperty(name="Fixed Texel Density", default=False,
                                    description="Pack at a given texel density instead of the "
                                    "largest that fits")
    texel_density: FloatProperty(name="Texel Density", default=512.0, min=1e-6,
                                 description="Texels per scene unit for every island")
    rotate: EnumProperty(name="Rotate", items=ROTATE_ITEMS, default='any')
    udim: BoolProperty(name="UDIM Tiles", default=False,
                       description="With a fixed texel density: islands that do not fit tile "
                       "1001 spill into 1002, 1003, ...")
    group: EnumProperty(name="Group", items=GROUP_ITEMS, default='none',
                        description="Pack the islands of one material or one object together")

    @classmethod
    def poll(cls, context):
        return bool(edit_mesh_objects(context))

    def draw(self, context):
        layout = self.layout
        layout.prop(self, "resolution")
        layout.prop(self, "padding")
        layout.prop(self, "rotate")
        layout.prop(self, "group")
        layout.prop(self, "use_texel_density")
        row = layout.row()
        row.active = self.use_texel_density
        row.prop(self, "texel_density")
        row = layout.row()
        row.active = self.use_texel_density
        row.prop(self, "udim")

    def pack_options(self):
        return PackOptions(
            resolution=self.resolution, padding_px=self.padding, rotate=self.rotate,
            texel_density=self.texel_density if self.use_texel_density else None,
            udim=self.udim and self.use_texel_density, group=self.group)

    def execute(self, context):
        t0 = time.perf_counter()
        try:
            options = self.pack_options()
            with object_mode(context) as objects:
                masks = [mesh_data.selection(ob.data)[2] for ob in objects]
                done = pack_atlas(objects, masks, options)
        except BDError as exc:
            self.report({'ERROR'}, str(exc))
            return {'CANCELLED'}
        if done is None:
            self.report({'WARNING'}, "No selected faces with UVs to pack")
            return {'CANCELLED'}
        self.report({'INFO'}, pack_message(*done) + f" ({time.perf_counter() - t0:.2f} s in all)")
        return {'FINISHED'}


classes = (UV_OT_bd_pack,)
