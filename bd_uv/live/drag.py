"""A drag in steps: a live session's pins moved from where they are to their targets, for
``deform`` to mend a deformation that would lay an island over itself."""
import numpy as np

from .session import LiveSession
from .steps import pin_similarity

__all__ = ["drag_to"]


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
