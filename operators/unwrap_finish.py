"""How ``uv.bd_unwrap`` ends (``unwrap.UV_OT_bd_unwrap``, both its synchronous and background
paths: ``background.BackgroundSolve`` calls ``_finish``): write back, pack (the atlas packer or
Blender's), re-certify what is stored putting back what fails, mark the added seams, colour and
report.
"""
import dataclasses

import bpy

from ..bd_uv.errors import BDError
from ..bd_uv.packing import PackOptions
from ..bd_uv.unwrapping.storage import with_predicted_headroom
from . import auto_seams, session
from .editmode import object_mode
from .pack import pack_atlas, pack_message


class UnwrapFinish:
    """``_finish`` and ``_pack`` of ``UV_OT_bd_unwrap``, which mixes this class in: they read its
    properties (pack, pack_shape, margin, bound, seams, stretch, ...)."""

    def _pack(self, context, written):
        """Pack the written islands: the atlas packer (islands holding a pinned UV stay where
        they are and the rest pack around their true shapes; when it cannot, e.g. a pinned island
        lies outside the square, or its layout is not certified: Blender's, said in the note), or
        Blender's. Returns the note for the report line."""
        if self.pack_shape != 'ATLAS':
            session.pack(context, written, self.margin, self.pack_shape)
            return ""
        options = PackOptions(resolution=self.pack_resolution, padding_px=self.pack_padding,
                              group=self.pack_group)
        try:
            with object_mode(context):
                obs = [bpy.data.objects.get(w.object_name) for w in written]
                todo = [(ob, w.pack_polygons) for ob, w in zip(obs, written) if ob is not None]
                done = pack_atlas([o for o, _ in todo], [m for _, m in todo], options)
        except BDError as exc:
            session.pack(context, written, self.margin, 'AABB')
            return f"packed by Blender's packer: {exc}"
        return pack_message(*done, head="packed: ") if done is not None else ""

    def _finish(self, context, batch, solved, seconds):
        """Write, pack, re-certify what is stored (putting back what fails), mark the added
        seams, colour, report.

        ``solved`` is an ``UnwrapResult``, or with Seams "Add Where Needed" an
        ``auto_seams.AutoSeams`` whose added seams are marked on every object something was
        written and kept on (in the operator's one undo step). The report line and the panel
        show the figures of the post-write check. FINISHED when anything was written and kept,
        as Blender's own Unwrap does when some islands fail; CANCELLED when nothing at all was
        written (with a WARNING saying why; no seam is marked then)."""
        auto = solved if isinstance(solved, auto_seams.AutoSeams) else None
        result = auto.result if auto is not None else solved
        stretch = self.stretch if self.seams == 'AUTO' or self.limit_stretch else None
        headroom = {}
        if stretch is None:   # islands whose faces float32 UVs would not resolve: re-solved now
            result, headroom = with_predicted_headroom(batch.V, batch.F, result)
        with object_mode(context):
            written = session.write_back(batch, result)
        verified, packed_note = None, ""
        if any(w.faces.any() for w in written):
            if self.pack:
                packed_note = self._pack(context, written)
            with object_mode(context):
                verified = session.verify_written(batch, result, written, stretch)
        summary = session.summarise(batch, result, written, seconds, verified, packed=self.pack,
                                    stretch=stretch)
        if auto is not None and summary.written and (len(auto.added) or auto.notes
                                                     or self.seams == 'AUTO'):
            with object_mode(context):
                marked = session.mark_seams(batch, written, auto.added)
            summary = dataclasses.replace(summary, message=(
                f"{summary.message}; {marked} seam{'s' if marked != 1 else ''} added, "
                f"{auto.charts} chart{'s' if auto.charts != 1 else ''}"
                + (" (see the marked seams in Edit Mode)" if marked else "")
                + atlas_note(auto.atlas_cuts)
                + "".join(f"; {note}" for note in auto.notes)))
        elif summary.written:
            cut = session.overlap_cuts(result)
            if len(cut):  # an island that overlapped itself was cut: show the artist where
                with object_mode(context):
                    marked = session.mark_seams(batch, written, cut)
                summary = dataclasses.replace(summary, message=(
                    f"{summary.message}; {marked} seam{'s' if marked != 1 else ''} marked where "
                    "overlapping islands were cut"))
        if summary.written and headroom:
            summary = dataclasses.replace(summary, message=f"{summary.message}; " + ", ".join(
                f"island {i} re-solved with stretch <= {S:g}" for i, S in headroom.items())
                + " (its conformal map shrank faces below what float32 UVs resolve)")
        if summary.written and packed_note:  # the layout's figures beside the map's, before notes
            head, sep, notes = summary.message.partition("; ")
            summary = dataclasses.replace(summary, message=f"{head}; {packed_note}{sep}{notes}")
        if summary.written and self.show_distortion:
            bound = summary.bound_certified if summary.bound_certified > 1 else self.bound
            session.show_distortion(context, written, bound)
        session.store(context.window_manager, summary, batch.face_count)
        self.report({summary.level}, summary.message)
        return {'FINISHED'} if summary.written else {'CANCELLED'}


def atlas_note(atlas):
    """The report's words on the atlas cuts (``AutoSeams.atlas_cuts``): "" when none."""
    if not atlas or not atlas["cuts"]:
        return ""
    n = atlas["cuts"]
    return (f"; of those seams, {n} atlas cut{'s' if n != 1 else ''} ({len(atlas['seams'])} "
            f"edges, length {atlas['length']:.3g}: a chart cut in two to pack tighter; turn off "
            "Atlas Cuts for none)")
