"""``bd_uv.unwrap``: the public entry point, above both ways of finding islands.

With ``seams_mode="needed"`` the mesh is repaired and only the islands that cannot be certified
as they are get seams (``bd_uv.seams.needed.unwrap_needed``). With ``seams_mode="auto"``
(``seams="auto"``) the seam search (``bd_uv.seams.unwrap_auto``) cuts the
mesh into charts, which it certifies through ``bd_uv.unwrapping.unwrap``; otherwise the given
seams go straight to ``bd_uv.unwrapping.unwrap``. Living here, above ``seams`` and
``unwrapping``, the choice needs no import from ``unwrapping`` back up to ``seams``.
"""
import dataclasses

import numpy as np

from .errors import OptionError
from .options import unwrap_options
from .seams.pack_shape import atlas_cuts_of
from .seams.needed import unwrap_needed
from .seams.repaired import unwrap_auto_repaired
from .unwrapping import unwrap as unwrap_given_seams


def unwrap(V, F, seams=None, pin_corners=None, pin_uv=None, *, initial_uv=None,
           face_groups=None, progress=None, cancel=None, options=None, precision=None,
           **values):
    """Map a triangle mesh to the plane with no flipped face and conformal distortion <= C.

    Parameters
    ----------
    V : (n,3) float array
    F : (m,3) int array
    seams : (s,2) int array, optional, vertex pairs of the edges to cut along (kept when seams
        are added); or "auto" / "needed", the same as ``seams_mode="auto"`` / ``"needed"`` with
        no given seams
    pin_corners, pin_uv, initial_uv, progress, cancel : as ``bd_uv.unwrapping.unwrap``'s
        (pins and ``initial_uv`` are refused where seams are added: the charts are not known
        before)
    face_groups : (m,) int array, optional, the polygon each triangle comes from: no cut, and no
        seam added, goes through one
    options : bd_uv.UnwrapOptions, optional (default: the defaults)
    precision : the float type ``V`` was stored in, optional (``np.float32`` for glTF, USD and
        Blender positions): faces thinner than one step of it at their coordinates are
        zero-area faces (``mesh.thinner_than_precision``): left out with them with
        ``seams_mode="needed"`` and, where two lie side by side, with "auto" (the mesh repaired
        before the search, ``seams.repaired``); with "marked" they refuse their island
        (``DegenerateFacesError``) at once, rather than after solves that cannot certify it as
        stored
    **values : UnwrapOptions fields replacing those of ``options``: ``bd_uv.unwrap(V, F,
        bound=3.0, method="arap")``

    Returns
    -------
    UnwrapResult

    Raises
    ------
    InvalidMeshError for a mesh that cannot be read, OptionError (a ValueError) naming a bad
    option, CancelledError when cancelled.
    """
    if isinstance(seams, str):
        if seams not in ("auto", "needed"):
            raise OptionError("seams", f"seams must be vertex pairs, 'auto' or 'needed', got "
                              f"{seams!r}")
        seams, values = None, {**values, "seams_mode": seams}
    opts = unwrap_options(options, **values)
    if opts.seams_mode == "marked":
        return unwrap_given_seams(V, F, seams, pin_corners, pin_uv, initial_uv=initial_uv,
                                  face_groups=face_groups, progress=progress, cancel=cancel,
                                  options=opts, precision=precision)
    if pin_corners is not None and len(pin_corners):
        raise OptionError("seams_mode", f"seams_mode={opts.seams_mode!r} does not take pins or "
                          "the current UVs: call bd_uv.seams.unwrap_auto for material groups, "
                          "or mark seams")
    if opts.seams_mode == "needed":
        return unwrap_needed(V, F, seams, polygons=face_groups, options=opts,
                             progress=progress, cancel=cancel, precision=precision)
    # face_groups (polygons) are kept whole by the seams added too: unwrap_auto's polygons.
    # A mesh with a defect the repair mends (a bow-tie, an edge of three faces, a duplicate or
    # zero-area face) is repaired and searched again (``seams.repaired``), not failed whole.
    res, added, info, _ = unwrap_auto_repaired(V, F, seams=seams, bound=opts.bound,
                                               stretch=opts.seams_stretch, method=opts.method,
                                               frames=opts.frames, cone=opts.cone,
                                               progress=progress, cancel=cancel,
                                               polygons=face_groups, atlas_cuts=opts.atlas_cuts,
                                               precision=precision)
    return dataclasses.replace(res, seams_added=np.asarray(added, dtype=np.int64).reshape(-1, 2),
                               atlas_cuts=atlas_cuts_of(info))
