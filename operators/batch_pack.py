"""How ``scripts/bd_uv_batch.py`` packs each object's written islands (``--pack``): with the
atlas packer (``pack.pack_atlas``, on the mesh data: no selection, mode or view layer needed) or
Blender's Pack Islands (``session.pack``, from Object Mode, in the view layer), and which packing
options it refuses as accepted and ignored.
"""
import bpy
import numpy as np

from ..bd_uv.errors import BDError
from ..bd_uv.layout import pack_summary
from . import session
from .pack import pack_atlas

PACK_SHAPES = ("ATLAS", "AABB", "CONVEX", "CONCAVE")
MARGIN = 0.001   # Blender's packer's margin by default


def pack_settings(args, arguments):
    """(the atlas packer's PackOptions or None, an error line or None): packing options that
    would be accepted and ignored are refused, as are bad values."""
    atlas = args.pack and args.pack_shape == "ATLAS"
    given = arguments.pack_options_given(args)
    if given and not atlas:
        return None, (f"{', '.join(given)} set the atlas packer: give --pack (its --pack-shape "
                      "ATLAS is the default)")
    if args.pack_shape != "ATLAS" and not args.pack:
        return None, f"--pack-shape {args.pack_shape} packs with --pack only"
    if args.margin is not None and (atlas or not args.pack):
        return None, ("--margin is Blender's packer's: give --pack --pack-shape "
                      "AABB|CONVEX|CONCAVE (the atlas packer's gap is --padding in texels)")
    if not atlas:
        return None, None
    try:
        return arguments.pack_options_of(args), None
    except BDError as exc:
        return None, str(exc)


def pack(written, args, atlas):
    """Pack each object's written islands, as the operator does: with the atlas packer when
    ``atlas`` (PackOptions; the entry gets its ``pack`` report, or a ``pack_note`` when it cannot
    and Blender's AABB packs instead), else Blender's Pack Islands with ``--pack-shape`` and
    ``--margin``. Islands with pinned UVs stay put.

    Each object is packed on its own, into its own UV space: packed together with another
    object's pinned island lying outside the unit square, Blender's packer shrank a whole object
    to a dot (1e-5 wide, where float32 UVs no longer hold its shape).
    """
    margin = MARGIN if args.margin is None else args.margin
    view_layer = bpy.context.view_layer
    for w in written:
        entry, ob, arrays, ok = w.entry, w.ob, w.arrays, w.ok
        polygons = np.zeros(len(ob.data.polygons), dtype=bool)
        polygons[arrays.tri_poly[ok]] = True
        # Both packers work on the active UV map: make it the one written, for the moment.
        layers = ob.data.uv_layers
        active = layers.active.name
        layers.active = layers[entry["uv_map"]]
        try:
            shape = args.pack_shape
            if atlas is not None:   # on the mesh data: no selection, mode or view layer needed
                try:
                    done = pack_atlas([ob], [polygons], atlas)
                except BDError as exc:
                    entry["pack_note"] = f"packed by Blender's packer (AABB): {exc}"
                    shape = "AABB"
                else:
                    if done is not None:
                        entry["pack"] = pack_summary(done[0], done[1])
                    continue
            if ob.name not in view_layer.objects:
                entry["pack_note"] = (f"not packed: {ob.name} is not in the view layer "
                                      f"{view_layer.name!r}, where Blender's packer works")
                continue
            _blender_pack(ob, ok, polygons, margin, shape)
        finally:
            layers.active = layers[active]


def _blender_pack(ob, ok, polygons, margin, shape):
    """Blender's Pack Islands on one object's polygons (Object Mode first: the file may have been
    saved in Pose Mode or another object's Edit Mode)."""
    view_layer = bpy.context.view_layer
    if view_layer.objects.active is not None and bpy.context.mode != 'OBJECT':
        bpy.ops.object.mode_set(mode='OBJECT')
    for other in view_layer.objects:
        other.select_set(False)
    ob.select_set(True)
    view_layer.objects.active = ob
    bpy.ops.object.mode_set(mode='EDIT')
    try:
        session.pack(bpy.context, [session.Written(ob.name, ok, polygons)], margin, shape)
    finally:
        bpy.ops.object.mode_set(mode='OBJECT')
