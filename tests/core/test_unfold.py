"""A disk whose conformal map within C lies over itself is unfolded, not cut (issue 21 item 2):
first its conformal map again with the angles capped at the boundary vertices it wraps round
(``capped``), else the bound search up to its first map that does not lie over itself
(``disk_auto.minimise_disk``, ``BoundSearch.search``'s ``enough`` behind its cheap ``ready``: the
boundary's turning number, ``disk_certificate.turning``).

Checked here from the stored UVs alone, independently of the code under test: each face's
distortion and orientation from its Jacobian in its own 3D frame (numpy's SVD,
``unwrap_contract.distortion_and_flips``), as float64 and as float32, and the boundary a simple
polygon wound counter-clockwise covering exactly the triangles' union (shapely).
"""
import numpy as np
import pytest

import bd_uv
from bd_uv.solvers import bound_search
from bd_uv.energies import JacobianOperators
from bd_uv.unwrapping import disk_certificate, one_disk
from helpers import load_off, rings
from unwrap_contract import assert_one_simple_disk, distortion_and_flips


# (mesh, seed face, faces at least, the way it unfolds): disks whose conformal map at C = 5 lies
# over itself
OVERLAPPING = [("three_peaks.off", 1829, 500, "projected"),
               ("three_peaks.off", 1251, 900, "angles_capped"),
               ("three_peaks.off", 2641, 300, "projected"), ("cow.off", 3451, 150, "angles_capped"),
               ("cow.off", 2676, 300, "angles_capped")]


@pytest.mark.parametrize("name, seed, faces, way", OVERLAPPING)
def test_a_disk_whose_conformal_map_overlaps_is_unfolded_and_certified(name, seed, faces, way):
    V, F = rings(*load_off(name), seed, faces)
    disk = one_disk.find(V, F)
    done, u, overlaps = one_disk.unwrap_disk(V, F, disk, 5.0, 0.0)
    assert done is None and overlaps        # flip-free within 5, lying over itself
    res = bd_uv.unwrap(V, F, bound=5.0)
    (r,) = res.islands
    assert r.status == "certified" and "unfolded" in r.flags and r.bound_certified == 5.0
    assert way in r.flags
    uv = res.corner_uv
    for stored in (uv, uv.astype(np.float32).astype(np.float64)):
        D, flipped = distortion_and_flips(V, F, stored)
        assert not flipped.any() and D.max() <= 5.0
    # the boundary: one simple polygon, counter-clockwise, whose inside is the triangles' union
    assert_one_simple_disk(V, F, uv, r, disk.island)
    # nearer the conformal map than the least C's map: not that map (its max above the least C)
    # and a mean below it, or within 0.1 % of it where the least C's mean is lowered last within
    # its max (``energy_within.weighted_lowered``: three_peaks 2641/300, 1.19355 against the
    # unfold's 1.19414)
    least = bd_uv.unwrap(V, F, bound="auto").islands
    assert len(least) > 1 or (r.max_distortion > least[0].bound_certified and (
        r.mean_distortion < least[0].mean_distortion
        or ("mean_lowered" in least[0].flags
            and r.mean_distortion < least[0].mean_distortion * (1 + 1e-3))))
    # no boundary vertex wrapped round: its faces' UV angles add up to less than 2 pi
    z = uv[..., 0] + 1j * uv[..., 1]
    angle = np.abs(np.angle((np.roll(z, -2, axis=1) - z) / (np.roll(z, -1, axis=1) - z)))
    theta = np.bincount(F.ravel(), angle.ravel(), len(V))
    assert theta[disk.island.vertices[disk.island.loops[0]]].max() < 2 * np.pi


def _square(k):
    t = np.linspace(0, 1, k, endpoint=False)
    return np.r_[t, 1 + 1j * t, (1 - t) + 1j, 1j * (1 - t)]


def test_the_turning_number_of_polygons():
    sq = _square(5)
    assert disk_certificate.turning(sq) == 1 and disk_certificate.turns_once(sq)
    assert disk_certificate.turning(sq[::-1]) == -1 and not disk_certificate.turns_once(sq[::-1])
    eight = np.exp(2j * np.pi * np.linspace(0, 1, 40, endpoint=False))
    eight = eight.real + 1j * np.sin(4 * np.pi * np.linspace(0, 1, 40, endpoint=False))
    assert disk_certificate.turning(eight) == 0              # a figure eight
    twice = np.exp(4j * np.pi * np.linspace(0, 1, 40, endpoint=False))
    assert disk_certificate.turning(twice) == 2              # round twice
    # a segment folding back exactly onto the last: its sign cannot be told, nothing refused
    spike = np.r_[sq[:3], sq[2] - 0.5j, sq[2], sq[3:]]
    assert disk_certificate.turning(spike) is None and disk_certificate.turns_once(spike)
    assert disk_certificate.turning(np.r_[sq[:4], np.nan, sq[4:]]) is None


def _search(V, F):
    disk = one_disk.find(V, F)
    _, u, _ = one_disk.unwrap_disk(V, F, disk, 5.0, 0.0)
    isl = disk.island
    ops = JacobianOperators(None, None, None, None, disk.area, isl.tris, disk.G[:, 0, :],
                            disk.G[:, 1, :])
    return bound_search.BoundSearch(ops, len(isl.vertices), isl.tris, isl.loops[0][:1],
                                    connected=True, ranks=disk.ranks), u, isl.loops[0]


def test_enough_is_asked_within_a_target_behind_ready_until_it_refuses():
    """Without ``ready``, ``enough`` is asked of each target's best at its end; with it, of each
    iterate that is the least yet and that ``ready`` passes, until ``enough`` refuses one, then
    again at the target's end only of a best not asked; never of one ``ready`` refuses."""
    V, F = rings(*load_off("three_peaks.off"), 1829, 500)
    asked = []

    def never(v):
        asked.append(v)
        return False

    targets = []

    def report(D, C):
        targets.append(C)
    bs, u, loop = _search(V, F)
    bs.search(u, None, report, None, None, never)
    assert 0 < len(asked) <= len(targets)               # at most once a target, at its end
    at_ends = len(asked)
    asked.clear(), targets.clear()
    bs, u, loop = _search(V, F)
    bs.search(u, None, report, None, None, never, lambda v: True)
    assert at_ends < len(asked) <= 2 * len(targets)     # within the targets too
    asked.clear(), targets.clear()
    bs, u, loop = _search(V, F)
    bs.search(u, None, report, None, None, never, lambda v: False)
    assert not asked and targets
    # the first new best that turns once and is one-to-one ends the search there
    seen = []

    def simple(v):
        seen.append(v)
        z = v.take(loop)
        return disk_certificate.simple_ccw_loop(np.stack([z.real, z.imag], axis=1))
    bs, u, loop = _search(V, F)
    us, D, _ = bs.search(u, None, None, None, None, simple,
                         lambda v: disk_certificate.turns_once(v.take(loop)))
    first = list(seen)
    assert first and np.array_equal(first[-1], us) and simple(us)
    assert not any(simple(v) for v in first[:-1])
    assert D < bs.distortion_of(u)


def test_a_face_rebuilt_from_its_angles_is_the_face():
    """``capped.from_angles`` of a face's own corner angles and area gives back its local
    corners (corner 0 at 0, corner 1 on the positive real axis), to rounding."""
    from bd_uv.unwrapping import capped
    V, F = rings(*load_off("cow.off"), 3451, 150)
    disk = one_disk.find(V, F)
    A = capped.corner_angles(disk.Z)
    assert np.allclose(A.sum(axis=1), np.pi) and (A > 0).all()
    Z = capped.from_angles(A, disk.area)
    assert np.allclose(Z, disk.Z, rtol=0, atol=1e-12 * np.abs(disk.Z).max())


def test_a_flat_map_is_not_searched_for_a_lower_max_but_is_for_an_enough():
    """``bound_search.FLAT``: the conformal map of a flat disk is an isometry up to round-off, so
    the least-C search makes no iteration; a search with an ``enough`` (the unfold of a flat
    island lying over itself: the USD sedan's body panel) still runs."""
    n = 8
    x, y = np.meshgrid(np.linspace(0, 1, n + 1), np.linspace(0, 1, n + 1), indexing="ij")
    V = np.stack([x.ravel(), y.ravel(), np.zeros(x.size)], axis=1)
    idx = np.arange((n + 1) ** 2).reshape(n + 1, n + 1)
    a, b, c, d = idx[:-1, :-1], idx[1:, :-1], idx[1:, 1:], idx[:-1, 1:]
    F = np.concatenate([np.stack([a, b, c], -1).reshape(-1, 3),
                        np.stack([a, c, d], -1).reshape(-1, 3)])
    vertices = one_disk.find(V, F).island.vertices
    iso = V[vertices, 0] + 1j * V[vertices, 1]       # the conformal map: the plane itself
    bs, _, loop = _search(V, F)
    u = iso.copy()
    D0 = bs.distortion_of(u)
    assert D0 - 1.0 <= bound_search.FLAT
    us, D, _ = bs.search(u)
    assert bs.iterations == 0 and D == D0 and np.array_equal(us, u)
    bs, _, loop = _search(V, F)
    us, D, _ = bs.search(iso.copy(), None, None, None, None, lambda v: False)
    assert bs.iterations > 0 and D <= D0     # it ran (an iterate the least yet would be asked)
