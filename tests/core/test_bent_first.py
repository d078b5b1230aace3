"""At a number C up to ``angle_start.BENT_UP_TO``, a disk whose conformal start flips two faces or
more (or flips and turns once) is bent into C without its angle start made first
(``angle_start.bent_first``); the angle start is made only where the unfold of a bent map lying
over itself asks for it (issue 21: three_peaks.off made it at C = 5 and never used it).

The maps are those made with the rule off, bit for bit, where the angle start is over C; each is
checked from its stored UVs alone: every face's distortion and orientation by numpy's SVD in its
own 3D frame (``unwrap_contract.distortion_and_flips``), float64 and float32, and the boundary a
simple polygon whose inside is the triangles' union (shapely). The premise (flipped faces, the
boundary's turning number) is recomputed from the conformal map's UVs in the same way.
"""
import numpy as np
import pytest

import bd_uv
from bd_uv.unwrapping import angle_start, one_disk
from helpers import load_off, rings
from unwrap_contract import assert_one_simple_disk, distortion_and_flips

# (mesh, seed face, faces at least, the bent map lies over itself): three_peaks' disks whose
# conformal start flips 19 and 28 faces, with angle starts of max 6.21 and 5.30 (over C = 5);
# the first one's bent map lies over itself and is unfolded from the angle start
BENT = [("three_peaks.off", 2481, 1000, True), ("three_peaks.off", 3275, 2000, False)]


def _turns(z):
    """The turning number of the closed polygon z (n,) complex, from its exterior angles."""
    e = np.roll(z, -1) - z
    return int(round(np.angle(np.roll(e, -1) / e).sum() / (2 * np.pi)))


def _premise(V, F, disk):
    """(faces the conformal start flips, its boundary's turning number), from its UVs."""
    _, u, _ = one_disk.unwrap_disk(V, F, disk, None, 0.0)
    _, flipped = distortion_and_flips(V, F, np.stack([u.real, u.imag], 1)[disk.island.tris])
    return int(flipped.sum()), _turns(u[disk.island.loops[0]])


def _counted(monkeypatch):
    """Count the calls of ``angle_start.angle_start`` (the module's own and ``unwrap``'s)."""
    calls = []
    made = angle_start.angle_start

    def counted(V, disk):
        calls.append(1)
        return made(V, disk)
    monkeypatch.setattr(angle_start, "angle_start", counted)
    return calls


def _certified(V, F, res, disk, C):
    (r,) = res.islands
    assert r.status == "certified" and r.bound_certified == C and r.overlap_free
    for stored in (res.corner_uv, res.corner_uv.astype(np.float32).astype(np.float64)):
        D, flipped = distortion_and_flips(V, F, stored)
        assert not flipped.any() and D.max() <= C
    assert_one_simple_disk(V, F, res.corner_uv, r, disk.island)
    return r


@pytest.mark.parametrize("mesh, seed, faces, overlaps", BENT)
def test_a_start_flipping_many_faces_is_bent_first_with_the_same_map(
        monkeypatch, mesh, seed, faces, overlaps):
    V, F = rings(*load_off(mesh), seed, faces)
    disk = one_disk.find(V, F)
    flips, turns = _premise(V, F, disk)
    assert flips >= angle_start.FLIPS_BENT
    v = angle_start.angle_start(V, disk)
    Dv, _ = distortion_and_flips(V, F, np.stack([v.real, v.imag], 1)[disk.island.tris])
    assert 5.0 < Dv.max() < 6.5                      # over C: never taken at C = 5
    calls = _counted(monkeypatch)
    res = bd_uv.unwrap(V, F, bound=5.0)
    r = _certified(V, F, res, disk, 5.0)
    # made only for the unfold of a bent map lying over itself
    assert len(calls) == (1 if overlaps else 0)
    assert ("unfolded" in r.flags) == overlaps and "projected" in r.flags
    monkeypatch.setattr(angle_start, "BENT_UP_TO", 0.0)     # the rule off: made first
    del calls[:]
    off = bd_uv.unwrap(V, F, bound=5.0)
    assert len(calls) == 1
    assert np.array_equal(off.corner_uv, res.corner_uv)


def test_above_bent_up_to_the_angle_start_is_made_first_and_taken_where_it_fits(monkeypatch):
    V, F = rings(*load_off("three_peaks.off"), 2481, 1000)
    disk = one_disk.find(V, F)
    calls = _counted(monkeypatch)
    res = bd_uv.unwrap(V, F, bound=8.0)
    r = _certified(V, F, res, disk, 8.0)
    assert len(calls) == 1 and "angle_start" in r.flags and "projected" not in r.flags


def test_a_start_flipping_one_face_and_turning_twice_still_takes_its_angle_start():
    """cow.off's 5243/400 disk: one flipped face, the boundary turning twice; its angle start
    (max 1.82) is taken at C = 5 as before."""
    V, F = rings(*load_off("cow.off"), 5243, 400)
    disk = one_disk.find(V, F)
    assert _premise(V, F, disk) == (1, 2)
    r = _certified(V, F, bd_uv.unwrap(V, F, bound=5.0), disk, 5.0)
    assert r.flags == ("angle_start",) and r.max_distortion < 2.0


def test_a_disk_map_measured_over_c_is_not_measured_again_by_the_batched_path(monkeypatch):
    """The general path starts from the disk's conformal map, which ``one_disk`` measured over
    C (it flips): the batched path's measure of it (``conformal_islands``) is not made, and
    the map is the one made with that measure, bit for bit."""
    import sys
    unwrap_module = sys.modules["bd_uv.unwrapping.unwrap"]
    V, F = rings(*load_off("three_peaks.off"), 3275, 2000)
    disk = one_disk.find(V, F)
    measured = []
    batched = unwrap_module._batched

    def counted(*args, **kwargs):
        measured.append(1)
        return batched(*args, **kwargs)
    monkeypatch.setattr(unwrap_module, "_batched", counted)
    res = bd_uv.unwrap(V, F, bound=5.0)
    _certified(V, F, res, disk, 5.0)
    assert not measured
    islands = unwrap_module.unwrap_islands

    def measuring(*args, **kwargs):
        return islands(*args, **dict(kwargs, over=False))
    monkeypatch.setattr(unwrap_module, "unwrap_islands", measuring)
    again = bd_uv.unwrap(V, F, bound=5.0)
    assert len(measured) == 1 and np.array_equal(again.corner_uv, res.corner_uv)
