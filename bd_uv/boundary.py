"""Bijective maps onto a boundary you choose (Lipman 2012, section 5, Theorems 5.1 and 5.2).

An orientation-preserving piecewise-linear map that takes a disk's boundary one-to-one onto a
simple polygon is a bijection onto the polygon's inside (Theorem 5.1), even a non-convex one; with
holes, the outer boundary and every hole must go one-to-one onto the boundary of a domain with as
many holes (Theorem 5.2). ``boundary_targets`` gives target positions for the outer boundary of an
island (circle, rectangle, or the polygon its pins give), which a fixed-boundary BD solve keeps as
pins; holes stay holes: ``fixed_boundary_map`` fills them for the solve with triangles held
orientation-preserving, so the filled disk maps bijectively (Theorem 5.1) and no hole crosses the
outer boundary. ``bijectivity.bijectivity_premises`` checks the premises on the result.
"""
import dataclasses
from dataclasses import dataclass

import numpy as np

from .bijectivity import BijectivityPremises, _cross, bijectivity_premises, oriented_loop
from .errors import InfeasibleError
from .frames import _corner_angles, frames_from_map, harmonic_map, hole_fans
from .geometry import face_areas, local_coordinates
from .metrics import conformal_distortion

HOMOTOPY_STEPS = (0.25, 0.5, 0.75, 1.0)
# Energy weight of the triangles filling holes during a fixed-boundary solve (relative to their
# area): small, so the island's own faces decide the map; not zero, so every vertex has energy.
FILL_WEIGHT = 1e-3

SHAPES = ("circle", "rectangle", "pinned")


def _loop_lengths(V, loop):
    return np.linalg.norm(V[np.roll(loop, -1)] - V[loop], axis=1)


def _corner_sum(V, tris, nv):
    """Sum of the face angles at each vertex (boundary vertices: the boundary's interior angle)."""
    ang = _corner_angles(local_coordinates(V, tris))
    return np.bincount(tris.ravel(), weights=ang.ravel(), minlength=nv)


def rectangle_corners(V, tris, loop, count=4):
    """The ``count`` boundary vertices whose interior angles best fit a rectangle's corners.

    Greedy on ``|angle - pi/2|`` (angles summed over the faces at each boundary vertex), keeping
    corners at least an eighth of the perimeter apart (arc length) so no side is empty.

    Returns
    -------
    (4,) int64 positions in ``loop`` (increasing)
    """
    L = _loop_lengths(V, loop)
    s = np.concatenate([[0.0], np.cumsum(L)[:-1]])
    per = L.sum()
    ang = _corner_sum(V, tris, len(V))[loop]
    order = np.argsort(np.abs(ang - 0.5 * np.pi), kind="stable")
    chosen = []
    for gap in (per / 8, per / 16, 0.0):
        chosen = []
        for i in order:  # at most b candidates; each step is a vector test
            d = np.abs(s[i] - s[chosen]) if chosen else np.array([per])
            if np.all(np.minimum(d, per - d) >= gap):
                chosen.append(int(i))
            if len(chosen) == count:
                return np.sort(np.array(chosen, dtype=np.int64))
    raise ValueError(f"a boundary of {len(loop)} vertices cannot carry {count} corners")


def _polygon_by_arc_length(V, loop, corner_pos, corner_uv):
    """Boundary positions: corners at ``corner_uv``, other vertices by arc length between them."""
    L = _loop_lengths(V, loop)
    s = np.concatenate([[0.0], np.cumsum(L)])  # s[i] = arc length at loop[i], s[b] = perimeter
    b = len(loop)
    cp = np.asarray(corner_pos)
    seg = np.searchsorted(cp, np.arange(b), side="right") - 1  # segment each vertex lies on
    seg[seg < 0] = len(cp) - 1  # before the first corner: the last side (wraps around)
    start, end = cp[seg], cp[(seg + 1) % len(cp)]
    s0 = s[start]
    s1 = np.where(end > start, s[end], s[end] + s[b])
    si = np.where(np.arange(b) >= start, s[np.arange(b)], s[np.arange(b)] + s[b])
    t = ((si - s0) / (s1 - s0))[:, None]
    P = np.asarray(corner_uv, dtype=np.float64)
    return (1 - t) * P[seg] + t * P[(seg + 1) % len(cp)]


def boundary_targets(V, tris, loops, shape, pins=None):
    """Target UVs of an island's outer boundary: a circle, a rectangle or the pinned polygon.

    Lipman 2012, section 5: kept as pins of a bounded-distortion solve, an orientation-preserving
    result maps the boundary one-to-one onto the target polygon and is then a bijection (Theorem
    5.1; with holes, filled during the solve by ``fixed_boundary_map``, Theorem 5.2 once
    ``bijectivity_premises`` holds).

    Parameters
    ----------
    V : (nv,3) float, the island's vertex positions
    tris : (k,3) int, its faces in island vertex ids (counter-clockwise seen from the normal side)
    loops : sequence of (b,) int, its boundary loops (``Island.loops``); the one longest in arc
        length is the outer boundary
    shape : "circle" (arc length, area = the island's 3D area), "rectangle" (corners at the four
        boundary vertices nearest a right angle, or at pinned ones; side lengths the mean of
        opposite sides' arc lengths, scaled to the island's 3D area) or "pinned" (the pinned
        boundary vertices are the polygon's corners at their pinned UVs, in boundary order; the
        others by arc length between them; needs >= 3 pins on the outer boundary)
    pins : tuple (idx (p,) int, uv (p,2) float), optional, pinned island vertices

    Returns
    -------
    idx : (b,) int64 outer-boundary vertices (ordered with the faces on the left), uv : (b,2)
        counter-clockwise; circle and rectangle have their bounding box starting at (0, 0)

    Raises
    ------
    ValueError for an unknown shape, pins that cannot define it, or a face with all three
    corners on the boundary that would be flat or flipped on the target (``check_targets``).
    """
    if shape not in SHAPES:
        raise ValueError(f"boundary shape must be one of {SHAPES}, got {shape!r}")
    V = np.asarray(V, dtype=np.float64)
    tris = np.asarray(tris, dtype=np.int64)
    lengths = [float(_loop_lengths(V, np.asarray(lp)).sum()) for lp in loops]
    loop = oriented_loop(tris, loops[int(np.argmax(lengths))])
    pin_idx = np.zeros(0, np.int64) if pins is None else np.asarray(pins[0], dtype=np.int64)
    pin_uv = np.zeros((0, 2)) if pins is None else np.asarray(pins[1], float).reshape(-1, 2)
    where = np.full(len(V), -1, dtype=np.int64)
    where[loop] = np.arange(len(loop))
    on = where[pin_idx] >= 0
    area = float(face_areas(V, tris).sum())
    if shape == "pinned":
        if on.sum() < 3:
            raise ValueError(f"boundary 'pinned' needs at least 3 pinned vertices on the outer "
                             f"boundary, got {int(on.sum())}")
        order = np.argsort(where[pin_idx[on]])
        uv = _polygon_by_arc_length(V, loop, where[pin_idx[on]][order], pin_uv[on][order])
        check_targets(tris, loop, uv)
        return loop, uv
    L = _loop_lengths(V, loop)
    if shape == "circle":
        s = np.concatenate([[0.0], np.cumsum(L)[:-1]]) / L.sum()
        R = np.sqrt(area / np.pi)
        uv = R * np.stack([1 + np.cos(2 * np.pi * s), 1 + np.sin(2 * np.pi * s)], 1)
        check_targets(tris, loop, uv)
        return loop, uv
    if on.sum() == 4:
        cp = np.sort(where[pin_idx[on]])
    elif on.sum() == 0:
        cp = rectangle_corners(V, tris, loop)
    else:
        raise ValueError(f"boundary 'rectangle' takes exactly 4 pinned corners on the outer "
                         f"boundary (or none), got {int(on.sum())}")
    cum = np.concatenate([[0.0], np.cumsum(L)])
    side = np.diff(np.concatenate([cum[cp], [cum[cp[0]] + cum[-1]]]))
    w, h = 0.5 * (side[0] + side[2]), 0.5 * (side[1] + side[3])
    k = np.sqrt(area / (w * h))
    corners = k * np.array([[0.0, 0.0], [w, 0.0], [w, h], [0.0, h]])
    uv = _polygon_by_arc_length(V, loop, cp, corners)
    check_targets(tris, loop, uv)
    return loop, uv


def check_targets(tris, idx, uv):
    """Raise when a face with all three corners pinned would be flat or flipped on the target.

    Such a face (e.g. a 90-degree boundary corner with one triangle, put on a straight side)
    leaves F_C empty for every C.

    Raises
    ------
    ValueError naming the faces
    """
    pos = np.full(int(max(tris.max(), np.max(idx))) + 1, -1, dtype=np.int64)
    pos[idx] = np.arange(len(idx))
    full = np.all(pos[tris] >= 0, axis=1)
    T = np.asarray(uv, dtype=np.float64)[pos[tris[full]]]
    e1, e2 = T[:, 1] - T[:, 0], T[:, 2] - T[:, 0]
    scale = np.maximum(np.sum(e1 * e1, 1), np.sum(e2 * e2, 1))
    bad = np.flatnonzero(full)[~(_cross(e1, e2) > 1e-9 * scale)]  # flat up to rounding
    if len(bad):
        raise ValueError(f"{len(bad)} face(s) (e.g. {bad[:5].tolist()}) have all three corners on "
                         "the target boundary and would be flat or flipped there; choose other "
                         "corners (pins) or split those faces")


def boundary_pins(V, F, shape, seams=None, pin_corners=None, pin_uv=None):
    """Pins for ``bd_uv.unwrap`` that put every island's outer boundary onto ``shape``.

    Each island's outer boundary gets ``boundary_targets``; holes stay free; other pins (inside
    the island or on holes) are kept. Passing the result as ``pin_corners=, pin_uv=`` to
    ``bd_uv.unwrap`` gives the fixed-boundary bounded-distortion map of section 5.

    Parameters
    ----------
    V : (n,3) float, F : (m,3) int, seams : (s,2) int, optional
    shape : "circle" | "rectangle" | "pinned"
    pin_corners : (p,) int flat corner indices (face * 3 + corner), optional; pin_uv : (p,2)

    Returns
    -------
    pin_corners : (q,) int64, pin_uv : (q,2) float64
    """
    from .mesh import islands as split_islands
    V = np.asarray(V, dtype=np.float64)
    F = np.asarray(F, dtype=np.int64)
    pc = np.zeros(0, np.int64) if pin_corners is None else np.asarray(pin_corners, np.int64)
    pu = np.zeros((0, 2)) if pin_uv is None else np.asarray(pin_uv, np.float64).reshape(-1, 2)
    out_c, out_uv = [], []
    pinned_face = pc // 3
    for isl in split_islands(V, F, seams):
        if isl.error is not None or not len(isl.loops):
            continue
        pos = np.full(len(F), -1, dtype=np.int64)
        pos[isl.faces] = np.arange(len(isl.faces))
        mine = pos[pinned_face] >= 0
        vid = isl.tris[pos[pinned_face[mine]], pc[mine] % 3]
        ids, first = np.unique(vid, return_index=True)
        pins = (ids, pu[mine][first]) if len(ids) else None
        idx, uv = boundary_targets(V[isl.vertices], isl.tris, isl.loops, shape, pins)
        target = np.full((len(isl.vertices), 2), np.nan)
        target[idx] = uv
        corners = isl.faces[:, None] * 3 + np.arange(3)[None, :]
        on = ~np.isnan(target[isl.tris][..., 0])
        out_c.append(corners[on])
        out_uv.append(target[isl.tris][on])
        keep = np.isnan(target[vid][:, 0])  # the island's other pins stay
        out_c.append(pc[mine][keep])
        out_uv.append(pu[mine][keep])
    if not out_c:
        return np.zeros(0, np.int64), np.zeros((0, 2))
    return np.concatenate(out_c).astype(np.int64), np.concatenate(out_uv)


@dataclass(frozen=True)
class FixedBoundaryMap:
    """A bounded-distortion map with its outer boundary fixed.

    Attributes
    ----------
    uv : (nv,2) float64, pinned vertices exactly at their targets
    max_distortion : float, conformal distortion (eq. 4.9), <= the bound
    premises : BijectivityPremises, checked on ``uv``
    solves : int
    """
    uv: np.ndarray
    max_distortion: float
    premises: BijectivityPremises
    solves: int


def fill_holes(Z, tris, nv, holes):
    """The island with every hole filled by a fan of triangles around a new centre vertex.

    Parameters
    ----------
    Z : (k,3) complex local corner coordinates, tris : (k,3) int, nv : int
    holes : sequence of (b,) int hole loops, faces on their left (``oriented_loop``)

    Returns
    -------
    Z_all : (k+q,3) complex, tris_all : (k+q,3) int64 (the fill after the island's faces,
    oriented like them), nv_all : int (the centre of hole h is vertex nv + h)
    """
    if not len(holes):
        return Z, tris, nv
    Zf, Tf = hole_fans(Z, tris, nv, holes)
    return np.concatenate([Z, Zf]), np.concatenate([tris, Tf]), nv + len(holes)


def fixed_boundary_map(V, tris, loops, idx, uv, method="dirichlet", bound=5.0, stretch=None,
                       cone="soc", cancel=None):
    """Minimise an energy over F_C with the vertices ``idx`` pinned at ``uv`` (section 5).

    Holes stay holes by construction: each is filled by a fan of triangles (``fill_holes``) held
    orientation-preserving only (``deform.LOOSE_BOUND``, energy weight ``FILL_WEIGHT``), so the
    filled disk's map is orientation-preserving with its boundary on the simple target polygon, a
    bijection by Theorem 5.1: the holes' images lie inside the target and apart from every other
    triangle. The fill is removed before the result is checked (``bijectivity_premises``).
    The frames come from the flip-free Tutte embedding onto a circle (``frames.harmonic_map``),
    turned by the rotation that best fits its pinned vertices to their targets (F_C only admits
    rotations within 90 degrees of the frames, so the embedding's arbitrary global rotation must
    go). When that space is empty the pins are reached in steps (``HOMOTOPY_STEPS``) from the
    fitted embedding's own positions, each step's frames from the last (eq. 4.21).

    Parameters
    ----------
    V : (nv,3) float, tris : (k,3) int, loops : sequence of (b,) int (``Island`` fields)
    idx : (p,) int, pinned island vertices (e.g. ``boundary_targets``' outer boundary, plus any
        interior pins); uv : (p,2) float, their targets
    method : an energy of ``deform.METHODS``
    bound : float >= 1
    stretch : (smin, smax) or None, singular-value bounds relative to the 3D geometry (sec. 6.3)
    cone : "soc" | "linf"
    cancel : object with ``is_set()``, optional (``CancelledError`` when set)

    Returns
    -------
    FixedBoundaryMap

    Raises
    ------
    InfeasibleError when no certified map was found.
    """
    from .deform import alpha_of, bounded_with_resets
    from .energies import jacobian_operators
    V = np.asarray(V, dtype=np.float64)
    tris = np.asarray(tris, dtype=np.int64)
    idx = np.asarray(idx, dtype=np.int64)
    uv = np.asarray(uv, dtype=np.float64).reshape(-1, 2)
    nv, k = len(V), len(tris)
    scale = np.sqrt(face_areas(V, tris).sum())
    Z = local_coordinates(V / scale, tris)
    # The outer loop holds the most targets; the holes are filled (``fill_holes``).
    rings = [oriented_loop(tris, lp) for lp in loops]
    outer = int(np.argmax([np.isin(r, idx).sum() for r in rings]))
    holes = [r for i, r in enumerate(rings) if i != outer]
    Z, tris_all, n_all = fill_holes(Z, tris, nv, holes)
    ops = jacobian_operators(Z, tris_all, n_all)
    loose = np.arange(len(tris_all)) >= k
    if holes:  # the fill's energy barely counts: it only keeps the holes' images inside
        ops = dataclasses.replace(ops, area=np.where(loose, FILL_WEIGHT * ops.area, ops.area))
    c = uv.mean(axis=0)
    val = ((uv[:, 0] - c[0]) + 1j * (uv[:, 1] - c[1])) / scale
    ut = harmonic_map(Z, tris_all, n_all, [rings[outer]])
    a = ut[idx] - ut[idx].mean()
    z = np.sum(np.conj(a) * val)  # least-squares similarity: embedding -> targets
    ut = ut * (z / np.sum(np.abs(a) ** 2)) if abs(z) > 0 else ut
    st = None if stretch is None else tuple(np.asarray(stretch, float))
    lo = loose if holes else None
    w = frames_from_map(alpha_of(ops, ut))
    u, solves, _ = bounded_with_resets(ops, idx, val, w, bound, method, 1e-3, st, cone,
                                      cancel, loose=lo)
    if u is None:
        start = ut[idx]
        for t in HOMOTOPY_STEPS:
            u, n, _ = bounded_with_resets(ops, idx, (1 - t) * start + t * val, w, bound, method,
                                          1e-3, st if t == 1.0 else None, cone, cancel, loose=lo)
            solves += n
            if u is None:
                raise InfeasibleError(f"no map within C = {bound:g} reaches the boundary targets "
                                      f"(stuck at {int(100 * t)}% of the way from a circle); "
                                      "raise the bound or choose another boundary")
            w = frames_from_map(alpha_of(ops, u))
    u = u[:nv]  # the fill's centre vertices go
    out = np.column_stack([u.real * scale + c[0], u.imag * scale + c[1]])
    out[idx] = uv
    D = conformal_distortion(V, tris, out[tris])
    premises = bijectivity_premises(out, tris, loops)
    if not (np.all(D <= bound * (1 + 1e-6)) and premises.orientation_preserving):
        raise InfeasibleError(f"the fixed-boundary map did not certify within C = {bound:g} once "
                              "the pins were written back; raise the bound slightly")
    return FixedBoundaryMap(out, float(D.max()), premises, solves)
