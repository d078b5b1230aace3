"""The rest shape of a live session when none is given: the island's own conformal map."""
import numpy as np

from ..errors import InfeasibleError
from ..frames import lscm_map
from ..geometry import face_areas, local_coordinates
from ..mesh import islands
from ..solvers.flip_free import flip_free_map

__all__ = ["conformal_rest"]


def conformal_rest(V, F):
    """The free-boundary least-squares conformal map (Levy et al. 2002) of an island, scaled so
    its UV area equals its 3D area and centred at the origin. Where it flips faces, the flip-free
    map nearest it within C = 5 (``solvers.flip_free``: projection iterations from it).

    Parameters
    ----------
    V : (n,3) float64
    F : (k,3) int64, one connected island

    Returns
    -------
    rest : (n,2) float64, every face counter-clockwise

    Raises
    ------
    InfeasibleError when no flip-free map was found (give the session a ``rest_uv``)
    """
    n = len(V)
    Z = local_coordinates(V, F)
    # Two pins far apart fix the similarity (the map is the same up to one for any two).
    a = int(F[0, 0])
    b = int(np.argmax(np.linalg.norm(V - V[a], axis=1)))
    u = lscm_map(Z, F, n, None, pins=(np.array([a, b]), np.array([0.0, 1.0 + 0j])))
    z = u[F]
    signed = 0.5 * ((z[:, 1] - z[:, 0]).conj() * (z[:, 2] - z[:, 0])).imag
    if np.all(signed < 0):
        u, signed = u.conj(), -signed
    if not np.all(signed > 0):
        u, signed = _flip_free(V, F, Z, u)
    if not np.all(signed > 0):
        raise InfeasibleError(f"the island's conformal map flips {int(np.sum(signed <= 0))} "
                              "faces; give the session a flip-free rest_uv (an unwrap)",
                              faces=np.flatnonzero(signed <= 0))
    u = (u - u.mean()) * np.sqrt(face_areas(V, F).sum() / signed.sum())
    return np.column_stack([u.real, u.imag])


def _flip_free(V, F, Z, u):
    isl = islands(V, F)
    if len(isl) != 1 or isl[0].error is not None:
        return u, np.zeros(len(F))
    loops = [isl[0].vertices[lp] for lp in isl[0].loops]       # back to the input's vertex ids
    ff, _ = flip_free_map(Z, F, len(V), loops, u)
    if ff is None:
        return u, np.zeros(len(F))
    z = ff[F]
    return ff, 0.5 * ((z[:, 1] - z[:, 0]).conj() * (z[:, 2] - z[:, 0])).imag
