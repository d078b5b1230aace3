"""A drag in steps: a live session's pins moved from where they are to their targets, and with it
``deform``'s mending of a deformation that would lay an island over itself."""
import numpy as np

from ..errors import OverlapError
from ..metrics import conformal_distortion, flipped_faces
from ..overlap import island_overlaps
from .session import LiveSession
from .steps import LIVE_METHODS, pin_similarity

__all__ = ["drag_to", "mend_overlap", "similarity_path"]


def similarity_path(P, T, steps):
    """Targets (steps, p, 2) from the pins ``P`` (p,2) to ``T`` (p,2): the similarity fitting
    them (``steps.pin_similarity``) taken in equal steps of its angle, log-scale and
    translation, and the rest of the move in equal steps."""
    s, t = pin_similarity(P, T)
    p = P[:, 0] + 1j * P[:, 1]
    c = p.mean()
    log_s = np.log(s) if abs(s) > 0 else 0j
    end = s * p + t
    out = []
    for f in np.arange(1, steps + 1) / steps:
        z = np.exp(f * log_s) * (p - c) + c + f * (s * c + t - c)
        z = z + f * ((T[:, 0] + 1j * T[:, 1]) - end)
        out.append(np.column_stack([z.real, z.imag]))
    out[-1] = np.array(T, dtype=np.float64)
    return out


def drag_to(rest, F, handles, positions, method, bound, steps=10, hold=30):
    """Drag the handles of a planar mesh from their rest positions to ``positions`` with a
    ``LiveSession`` (every frame certified: no flip, distortion <= C, no overlap).

    Parameters
    ----------
    rest : (n,2) float64, the rest shape (counter-clockwise faces, overlap-free)
    F : (k,3) int64
    handles : (h,) int64, positions : (h,2) float64
    method : "arap" | "lscm" | "dirichlet"
    bound : float C > 1
    steps : int, frames along the path; hold : int, further frames at the targets at most

    Returns
    -------
    frame : LiveFrame, the last frame; ``pin_error == 0`` when the handles reached their targets
    """
    with LiveSession(rest, F, handles, bound=bound, method=method, rest_uv=rest) as s:
        path = similarity_path(rest[handles], np.asarray(positions, dtype=np.float64), steps)
        for T in path:
            frame = s.update(T)
        for _ in range(hold):
            if frame.pin_error == 0:
                break
            frame = s.update(path[-1])
        return frame


def mend_overlap(V2, F, handles, positions, method, bound, stretch, cone, ov):
    """A deformation (``bd_uv.deform``) laid the island over itself: drag the handles there in
    certified steps and return (uv (n,2), distortion (m,)) of the map reached, handles exact, or
    raise ``OverlapError`` saying why not.

    Parameters
    ----------
    V2 : (n,2) rest positions, F : (m,3), handles : (h,) int, positions : (h,2)
    method, bound, stretch, cone : ``deform``'s options (mended only for the live methods, no
        stretch bounds, the cone F_C)
    ov : overlap.IslandOverlap of the direct solve (for the message)
    """
    what = (f"the deformation would lay the island over itself ({int(ov.crossings[0])} crossing "
            f"boundary segment pairs, {int(ov.bad_loops[0])} loops on the wrong side)")
    if method not in LIVE_METHODS or stretch is not None or cone != "soc":
        raise OverlapError(what + f"; it is mended only for methods {LIVE_METHODS} without "
                           "stretch bounds: move the handles less or pin more of the boundary")
    if bound <= 1.0:
        raise OverlapError(what + "; raise C above 1 to mend it")
    frame = drag_to(V2, F, handles, positions, method, float(bound))
    if frame.pin_error > 0:
        raise OverlapError(what + ", and no overlap-free map within C meets the handles "
                           f"(dragging them there in certified steps got within "
                           f"{frame.pin_error:.3g}): move the handles less, pin more of the "
                           "boundary or raise C")
    uv = frame.uv.copy()
    uv[handles] = positions
    corner = uv[F]
    V3 = np.column_stack([V2, np.zeros(len(V2))])
    D = conformal_distortion(V3, F, corner)
    ok = island_overlaps(F, corner, np.zeros(len(F), dtype=np.int64), 1).overlap_free[0]
    if flipped_faces(V3, F, corner).any() or not np.all(D <= bound) or not ok:
        raise OverlapError(what + "; the mended map did not certify: move the handles less")
    return uv, D
