"""``bd_uv.unwrap``: the public entry point, above both ways of finding islands.

``seams="auto"`` goes to the seam search (``bd_uv.seams.unwrap_auto``), which itself certifies
its charts with ``bd_uv.unwrapping.unwrap``; any other ``seams`` (vertex pairs, or None) goes
straight to ``bd_uv.unwrapping.unwrap``. Living here, above ``seams`` and ``unwrapping``, the
choice needs no import from ``unwrapping`` back up to ``seams``.
"""
from .seams import unwrap_auto
from .seams.needed import AUTO_STRETCH, unwrap_needed
from .unwrapping import unwrap as unwrap_islands_of_seams


def unwrap(V, F, seams=None, pin_corners=None, pin_uv=None, method="lscm", bound=5.0,
           frames="auto", initial_uv=None, raise_bound=True, bound_limit=1000.0, cone="soc",
           time_budget=None, overlap="cut", face_groups=None, stretch=None, boundary="free",
           progress=None, cancel=None):
    """Map a triangle mesh to the plane with no flipped face and conformal distortion <= C.

    The parameters, return value and errors are those of ``bd_uv.unwrapping.unwrap``, and:

    seams : (s,2) int array, optional, vertex pairs of the edges to cut along; or "auto": cut
        every island that cannot be certified as it is into certified disk charts
        (``bd_uv.seams.unwrap_auto``; there ``stretch`` is 2 unless given, ``face_groups`` are
        the polygons no seam may cross, and pins, ``frames="input-uv"``, a fixed ``boundary``
        and ``bound="auto"`` are refused with a ValueError); or "needed": repair the mesh and
        add seams only to islands that cannot be certified at C as they are
        (``bd_uv.seams.needed.unwrap_needed``, the command line's default; to keep seams you
        marked, call it with ``seams=``); the same refusals as "auto"; ``stretch`` limits the
        charts it cuts (2 unless given) and, when given, every island

    Returns
    -------
    UnwrapResult
    """
    if isinstance(seams, str):
        if seams not in ("auto", "needed"):
            raise ValueError(f"seams must be vertex pairs, 'auto' or 'needed', got {seams!r}")
        if boundary != "free":
            raise ValueError(f"seams={seams!r} makes free-boundary charts; boundary= needs "
                             "boundary='free' there")
        if bound == "auto":
            raise ValueError(f"seams={seams!r} needs a numeric bound C")
        if (pin_corners is not None and len(pin_corners)) or frames == "input-uv":
            raise ValueError(f"seams={seams!r} does not take pins or the current UVs: call "
                             "bd_uv.seams.unwrap_auto for material groups, or mark seams")
        if seams == "needed":
            return unwrap_needed(V, F, bound=bound,
                                 stretch=AUTO_STRETCH if stretch is None else stretch,
                                 marked_stretch=stretch, polygons=face_groups, method=method,
                                 frames=frames, cone=cone, overlap=overlap, progress=progress,
                                 cancel=cancel)[0]
        # face_groups (polygons) are kept whole by the seams added too: unwrap_auto's polygons.
        return unwrap_auto(V, F, bound=bound, stretch=2.0 if stretch is None else stretch,
                           method=method, frames=frames, cone=cone, progress=progress,
                           cancel=cancel, polygons=face_groups)[0]
    return unwrap_islands_of_seams(
        V, F, seams=seams, pin_corners=pin_corners, pin_uv=pin_uv, method=method, bound=bound,
        frames=frames, initial_uv=initial_uv, raise_bound=raise_bound, bound_limit=bound_limit,
        cone=cone, time_budget=time_budget, overlap=overlap, face_groups=face_groups,
        stretch=stretch, boundary=boundary, progress=progress, cancel=cancel)
