"""``seams="auto"`` on a messy mesh: the seam search of a mesh repaired first where it needs it.

``unwrap_auto`` takes the mesh as it is: a bow-tie vertex, an edge of three faces, faces
oriented against each other, a duplicate or a zero-area face fails the whole island it is in
(Online3DViewer's ``cow.ply``, 5,804 faces with 13 bow-tie vertices: 0 of 1 islands, "split the
vertex (Mesh > Split)", a Blender menu named to a command-line user), where the default seams
mode (``seams.needed``) repairs such a mesh and certifies every piece (51 of 51 islands). Here the
search runs as it is; only where an island failed for a defect ``repair.repair_mesh`` mends is
the mesh repaired (bow-ties split, such edges cut, duplicates and zero-area faces left out) and
searched again, and the result given on the input's faces and vertices (``needed.result_on_input``:
a duplicate gets its twin's UVs, zero-area faces one failed island). A clean mesh pays nothing
(the repair alone is 4 ms of suzanne's 90 and 58 ms of camel's 760).
"""
import dataclasses

import numpy as np

from ..errors import (DegenerateFacesError, DuplicateFacesError, NonFiniteError,
                      NonManifoldError, OrientationError)
from ..repair import flat_at_precision, repair_mesh
from .auto import unwrap_auto
from .needed import result_on_input

# the island failures a repair mends
REPAIRABLE = (NonManifoldError, DegenerateFacesError, DuplicateFacesError, NonFiniteError,
              OrientationError)


def needs_repair(result):
    """Did an island of ``result`` (an UnwrapResult) fail for a defect the repair mends?"""
    return any(isinstance(r.error, REPAIRABLE) for r in result.islands)


def unwrap_auto_repaired(V, F, seams=None, polygons=None, method="lscm", precision=None,
                         **search):
    """``unwrap_auto(V, F, seams=seams, polygons=polygons, method=method, **search)``, on the
    repaired mesh where an island of the mesh as it is failed for a defect the repair mends.
    ``precision``: the float type V was stored in (``bd_uv.unwrap``'s): the repair then leaves
    out, as zero-area, the faces it cannot tell from a line, as ``seams.needed`` does (a glTF or
    USD mesh; a flipped byte in a crate file's points made 19 such faces certified in float64
    and flat as written). Such faces make the repair run first: no store in that float type
    keeps two side by side apart, so the search's chart holding them fails as stored at any
    stretch (a grid split by a strip one float32 step high, as a GLB: "0/1 mesh(es) certified:
    nothing written", where the default seams wrote it); and one alone, certified in float64,
    may be cut off by the overlap cut as a piece of its own that no store certifies (found by
    the polygon fuzz contract: a USD sheet with a face hanging on its side, whose third corner
    float32 moved off the side's line, failed whole with --seams auto). ``batch.unwrap_job``
    passes ``precision`` only for side-by-side faces, or to run again after such a face failed;
    ``seams.needed`` leaves every such face out alike.

    Returns
    -------
    (UnwrapResult over the input faces, added (k,2) int64 input vertex pairs, info as
    ``unwrap_auto``'s with ``atlas_seams`` in input vertices, the ``repair.Repair`` or None
    where the mesh was searched as it is); the result's ``repair`` names what was repaired
    """
    def as_it_is():
        return unwrap_auto(V, F, seams=seams, polygons=polygons, method=method, **search)
    flat = precision is not None and flat_at_precision(V, F, precision) is not None
    if not flat:
        res, added, info = as_it_is()
        if not needs_repair(res):
            return res, added, info, None
    rep = repair_mesh(V, F, precision)
    if not rep.changed or not len(rep.F):   # nothing mended, or nothing left to solve: the
        return as_it_is() + (None,) if flat else (res, added, info, None)   # islands say why
    poly = None if polygons is None else np.asarray(polygons, np.int64)[rep.faces]
    part, found, info = unwrap_auto(rep.V, rep.F, seams=rep.seams(seams), polygons=poly,
                                    method=method, **search)
    res = result_on_input(part, rep, np.asarray(F, np.int64), method)
    src = rep.vertex_source
    found = np.asarray(found, np.int64).reshape(-1, 2)
    added = (np.unique(np.sort(src[found], axis=1), axis=0) if len(found)
             else found)
    atlas = np.asarray(info["atlas_seams"], np.int64).reshape(-1, 2)
    info = dict(info, atlas_seams=np.sort(src[atlas], axis=1) if len(atlas) else atlas)
    return dataclasses.replace(res, repair=tuple(rep.notes())), added, info, rep
