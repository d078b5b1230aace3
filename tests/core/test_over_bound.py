"""A numeric bound asked of an island whose conformal map is flip-free but over it
(``unwrapping.searched.over_bound``): the bound search lowers the map instead of projection
iterations, raises an unreachable C to the map it finds, and stands in for the raise's conic
solves. Checked by distortion recomputed from the UVs (``helpers.reference_distortion``)."""
import numpy as np
import pytest
import trimesh

import bd_uv
from helpers import reference_distortion


def _sphere_with_a_hole(sub):
    """An icosphere with the faces round its top vertex removed: a disk whose conformal map is
    flip-free with max distortion about 3.7, and whose least certified C is about 2.5."""
    s = trimesh.creation.icosphere(subdivisions=sub)
    V, F = np.asarray(s.vertices), np.asarray(s.faces)
    keep = ~np.any(F == np.argmax(V[:, 2]), axis=1)
    used, inv = np.unique(F[keep], return_inverse=True)
    return V[used], inv.reshape(-1, 3)


def _checked(V, F, res):
    (isl,) = res.islands
    assert isl.status == "certified"
    D, flipped = reference_distortion(V, F, res.corner_uv)
    assert not flipped.any() and D.max() <= isl.bound_certified
    return isl, D


@pytest.mark.parametrize("sub", [2, 3])
def test_a_bound_out_of_reach_is_raised_to_the_searched_map(sub):
    """C = 2 (out of reach) and C = 2.4 (below the least C found, 2.52-2.54): certified at the
    bound search's map, as ``auto`` finds it; the raise's conic solves reached 3.72 and 3.81."""
    V, F = _sphere_with_a_hole(sub)
    D0, _ = reference_distortion(V, F, bd_uv.unwrap(V, F, bound=50.0).corner_uv)
    assert 3.5 < D0.max() < 4.0                       # the conformal map: flip-free, over 2.4
    auto, Da = _checked(V, F, bd_uv.unwrap(V, F, bound="auto"))
    for C, solves in ((2.0, 0), (2.4, 1)):
        isl, D = _checked(V, F, bd_uv.unwrap(V, F, bound=C))
        assert {"bound_raised", "projected"} <= set(isl.flags) and isl.solves == solves
        assert isl.bound_certified <= 2.6 and isl.bound_certified <= auto.bound_certified * 1.001
        assert D.max() >= C                           # raised: the map is not within C


def test_a_reachable_bound_and_no_raising_keep_their_paths():
    """C = 3 is reached by the conic solve as before (certified at 3, one solve, mean 1.151);
    without raising, C = 2 is refused as before."""
    V, F = _sphere_with_a_hole(3)
    isl, D = _checked(V, F, bd_uv.unwrap(V, F, bound=3.0))
    assert isl.bound_certified == 3.0 and "bound_raised" not in isl.flags and isl.solves == 1
    assert D.max() <= 3.0 and isl.mean_distortion < 1.16
    res = bd_uv.unwrap(V, F, bound=2.0, raise_bound=False)
    (isl,) = res.islands
    assert isl.status == "failed" and type(isl.error) is bd_uv.InfeasibleError
