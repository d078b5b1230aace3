"""One unwrap of the meshes in Edit Mode, shared by the synchronous and the background paths.

The steps live in one module each, and this module is the one name the operator and the batch
script call them by (a test substitutes ``session.pack``):

- reading, ``gather``: every object's selected faces copied into one concatenated problem
  (islands never span objects, so one ``bd_uv.unwrap`` call solves them all), and the core's
  arguments for it (``unwrap_arguments``, ``auto_arguments``, ``needed_arguments``,
  ``polygon_ids``);
- writing, ``write_back``: each object re-fetched, checked it did not change meanwhile, the
  certified islands written; ``pack`` (Blender's own ``uv.pack_islands``), ``mark_seams``,
  ``overlap_cuts``, ``show_distortion``;
- checking, ``verify``: every written island certified again from the UVs as stored, those that
  fail put back (``verify_written``);
- reporting, ``report``: what is stored turned into the report line and the panel's figures, in
  Blender's terms (faces are polygons) (``summarise``, ``failure_text``, ``store``).
"""
from .gather import (Batch, Part, UserError, auto_arguments, gather, needed_arguments,
                     polygon_ids, unwrap_arguments)
from .report import (LISTED, METHOD_LABELS, Summary, failure_text, store,
                     summarise)
from .verify import Checked, Verified, verify_written
from .write_back import (Written, mark_seams, overlap_cuts, pack, show_distortion,
                         write_back)

__all__ = ["Batch", "Part", "UserError", "auto_arguments", "gather", "needed_arguments",
           "polygon_ids",
           "unwrap_arguments", "LISTED", "METHOD_LABELS", "Summary", "failure_text", "store",
           "summarise", "Checked", "Verified", "verify_written", "Written", "mark_seams",
           "overlap_cuts", "pack", "show_distortion", "write_back"]
