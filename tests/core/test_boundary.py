"""Bijective maps onto a chosen boundary (Lipman 2012, section 5), checked independently:
SVD of each face's map, boundary positions against the target shape, overlap of every pair."""
import numpy as np
import pytest

import bd_uv
from bd_uv.boundary import (bijectivity_premises, boundary_pins, boundary_targets,
                            fixed_boundary_map, oriented_loop)
from helpers import grid, reference_distortion
from planar import circle, mesh_polygon, overlapping_pairs, square

L_POLYGON = np.array([[0, 0], [2, 0], [2, 1], [1, 1], [1, 2], [0, 2]], float)


def lift(V2):
    return np.column_stack([V2, 0.3 * np.exp(-2 * (V2 ** 2).sum(1))])


def seg_distance(P, A, B):
    """Distance of points P (n,2) to the segments A-B (s,2), (n,s)."""
    d = B - A
    t = np.clip(np.einsum("nsk,sk->ns", P[:, None] - A[None], d) / np.sum(d * d, 1), 0, 1)
    return np.linalg.norm(P[:, None] - (A[None] + t[..., None] * d[None]), axis=2)


def unwrap_onto(V, F, shape):
    pc, pu = boundary_pins(V, F, shape)
    res = bd_uv.unwrap(V, F, pin_corners=pc, pin_uv=pu, bound=5.0)
    assert res.certified
    assert np.array_equal(res.corner_uv.reshape(-1, 2)[pc], pu)  # pins kept exactly
    D, flipped = reference_distortion(V, F, res.corner_uv)
    assert not flipped.any() and D.max() <= 5.0 * (1 + 1e-6)
    r = res.islands[0]
    assert overlapping_pairs(r.uv, r.tris) == 0
    isl = bd_uv.islands(V, F)[0]
    assert bijectivity_premises(r.uv, r.tris, isl.loops).bijective
    return r, isl


def test_circle():
    V2, F = mesh_polygon(circle(40), area=0.01)
    V = lift(V2)
    r, isl = unwrap_onto(V, F, "circle")
    b = r.uv[isl.loops[0]]
    R = np.sqrt(bd_uv.geometry.face_areas(V, F).sum() / np.pi)  # UV area = 3D area
    assert np.allclose(np.linalg.norm(b - [R, R], axis=1), R, rtol=0, atol=1e-12)


def test_rectangle_corners_at_the_grid_corners():
    V, F = grid(12, 10, lambda x, y: 0.2 * np.sin(3 * x) * y)
    r, isl = unwrap_onto(V, F, "rectangle")
    b = r.uv[isl.loops[0]]
    lo, hi = b.min(0), b.max(0)
    on_side = np.min(np.abs(np.concatenate([b - lo, b - hi], 1)), axis=1)
    assert on_side.max() < 1e-12
    corner_ids = [0, 11, 108, 119]  # the grid's four corners (input vertex ids)
    cu = {tuple(np.round(r.uv[np.flatnonzero(r.vertices == c)[0]] - lo, 12)) for c in corner_ids}
    w, h = hi - lo
    assert cu == {(0.0, 0.0), (round(w, 12), 0.0), (0.0, round(h, 12)),
                  (round(w, 12), round(h, 12))}


def test_pinned_nonconvex_polygon_with_two_free_holes():
    holes = [circle(12, 0.3, (0.2, 0.1))[::-1], circle(10, 0.2, (-0.5, -0.4))[::-1]]
    V2, F = mesh_polygon(square(8), holes, [[0.2, 0.1], [-0.5, -0.4]], area=0.008)
    V = lift(V2)
    isl = bd_uv.islands(V, F)[0]
    assert len(isl.loops) == 3
    lengths = [np.linalg.norm(V[isl.vertices][np.roll(lp, -1)] - V[isl.vertices][lp], axis=1)
               .sum() for lp in isl.loops]
    outer = oriented_loop(isl.tris, isl.loops[int(np.argmax(lengths))])
    P = V2[isl.vertices[outer]]
    # corners: square corners, and the middle of the top side for the reflex corner
    at = [int(np.argmin(np.linalg.norm(P - c, axis=1)))
          for c in [[-1, -1], [1, -1], [1, 1], [0, 1], [-1, 1], [-1, 0]]]
    idx, uv = boundary_targets(V[isl.vertices], isl.tris, isl.loops, "pinned",
                               (outer[at], L_POLYGON))
    res = fixed_boundary_map(V[isl.vertices], isl.tris, isl.loops, idx, uv, bound=5.0)
    assert np.array_equal(res.uv[idx], uv)
    assert seg_distance(uv, L_POLYGON, np.roll(L_POLYGON, -1, 0)).min(1).max() < 1e-12
    D, flipped = reference_distortion(V[isl.vertices], isl.tris, res.uv[isl.tris])
    assert not flipped.any() and D.max() <= 5.0 * (1 + 1e-6)
    assert overlapping_pairs(res.uv, isl.tris) == 0
    assert res.premises.bijective
    # the holes were free: not on the pinned polygon
    hole = isl.loops[int(np.argmin(lengths))]
    assert seg_distance(res.uv[hole], L_POLYGON, np.roll(L_POLYGON, -1, 0)).min() > 1e-3


def test_premises_fail_on_a_flip_and_on_a_crossing_boundary():
    V2, F = mesh_polygon(square(4), area=0.05)
    isl = bd_uv.islands(lift(V2), F)[0]
    uv = V2[isl.vertices].copy()
    assert bijectivity_premises(uv, isl.tris, isl.loops).bijective
    inner = np.setdiff1d(np.arange(len(uv)), isl.loops[0])
    bad = uv.copy()
    bad[inner[0]] = [5.0, 5.0]  # pulled outside: flips faces, boundary still simple
    p = bijectivity_premises(bad, isl.tris, isl.loops)
    assert not p.orientation_preserving and not p.bijective
    twisted = uv.copy()
    lp = isl.loops[0]
    twisted[lp[[0, 2]]] = twisted[lp[[2, 0]]]  # two boundary vertices swapped: crossing edges
    p = bijectivity_premises(twisted, isl.tris, isl.loops)
    assert not p.boundary_simple and not p.bijective


def test_bad_shape_and_too_few_pins():
    V, F = grid(4, 4)
    with pytest.raises(ValueError):
        boundary_pins(V, F, "hexagon")
    with pytest.raises(ValueError, match="at least 3"):
        boundary_pins(V, F, "pinned", pin_corners=[0, 1], pin_uv=[[0, 0], [1, 0]])


def test_rectangle_corners_chosen_by_pins_straighten_a_curved_strip():
    """Trim-sheet use: a bent strip, four pinned vertices (not its geometric corners) become the
    rectangle's corners; their pinned UVs only choose the corners."""
    V, F = grid(16, 4)
    ang = V[:, 0] * np.pi  # bend the strip into a half ring
    V = np.column_stack([(1 + V[:, 1]) * np.cos(ang), (1 + V[:, 1]) * np.sin(ang), 0.2 * V[:, 1]])
    corners = np.array([1, 15, 63, 48])  # 1: one step in from the corner 0, which goes on a side
    fc = np.array([int(np.flatnonzero(F.ravel() == v)[0]) for v in corners])
    pc, pu = boundary_pins(V, F, "rectangle", pin_corners=fc, pin_uv=np.zeros((4, 2)))
    res = bd_uv.unwrap(V, F, pin_corners=pc, pin_uv=pu, bound=5.0)
    assert res.certified
    r = res.islands[0]
    D, flipped = reference_distortion(V, F, res.corner_uv)
    assert not flipped.any() and D.max() <= 5.0 * (1 + 1e-6)
    b = r.uv[bd_uv.islands(V, F)[0].loops[0]]
    lo, hi = b.min(0), b.max(0)
    assert np.min(np.abs(np.concatenate([b - lo, b - hi], 1)), axis=1).max() < 1e-12
    at = r.uv[[int(np.flatnonzero(r.vertices == c)[0]) for c in corners]]
    assert np.all(np.min(np.abs(np.stack([at - lo, at - hi], 0)), axis=0) < 1e-12)  # corners
    assert overlapping_pairs(r.uv, r.tris) == 0


def test_a_corner_triangle_on_a_straight_side_is_refused_with_its_face():
    V, F = grid(16, 4)
    corners = np.array([1, 14, 63, 48])  # puts grid corner 15 (one triangle) on a straight side
    fc = np.array([int(np.flatnonzero(F.ravel() == v)[0]) for v in corners])
    with pytest.raises(ValueError, match="all three corners"):
        boundary_pins(V, F, "rectangle", pin_corners=fc, pin_uv=np.zeros((4, 2)))
