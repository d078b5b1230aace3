"""Target positions for an island's outer boundary (Lipman 2012, section 5): a circle, a
rectangle or the polygon its pins give, checked so that no face with three corners on the target
is flat or flipped there; ``boundary_pins`` turns them into ``bd_uv.unwrap`` pins per island.
"""
import numpy as np

from ..bijectivity import _cross, oriented_loop
from ..geometry import corner_angles, face_areas, local_coordinates

SHAPES = ("circle", "rectangle", "pinned")


def _loop_lengths(V, loop):
    return np.linalg.norm(V[np.roll(loop, -1)] - V[loop], axis=1)


def _corner_sum(V, tris, nv):
    """Sum of the face angles at each vertex (boundary vertices: the boundary's interior angle)."""
    ang = np.abs(corner_angles(local_coordinates(V, tris)))
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
    from ..mesh import islands as split_islands
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
