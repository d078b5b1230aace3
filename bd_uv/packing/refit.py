"""A square layout checked exactly, and moved as one: to the square's low corner, or onto the
charts' exact outlines (those before their simplification) for the compaction (:mod:`.compact`).
"""
import numpy as np

from .nest import Placement, placed_bounds, rotations

# the compaction moves the charts' exact outlines, not the nesting's (simplified within tol:
# 2 tol more in every gap and tol at the edges), with this fraction of tol as their margin
# (few more points: cow 1,470 against 1,415, camel 2,476 against 2,155, suzanne the same);
# from the same nested layouts and CPU budget, seeds 0-3: camel 0.6959 -> 0.7003, suzanne
# 0.5992 -> 0.6042, dino 0.6771 -> 0.6800, cow 0.7023 -> 0.7034, eight 0.5862 -> 0.5865
EXACT_TOL = 0.05
# ... and at least this fraction of the square's side: float32 rounds a coordinate in [0.5, 1)
# by up to 3e-8, a distance by up to about 1e-7 of the side (0.005 texel at 65,536 px)
ROUNDING = 1e-6


def fits(outlines, angle, shift, S, pad, pm, tol):
    """Exactly: every outline inside [e, S - e]^2 (e = pad S / 2 + tol) and every two at
    least pm S + 2 tol apart."""
    import shapely
    R = rotations(angle)
    placed = [o @ R[i].T + shift[i] for i, o in enumerate(outlines)]
    Q = np.concatenate(placed)
    e = 0.5 * pad * S + tol - 1e-12 * S     # (rounding of the nesting's own placement)
    if Q.min() < e or Q.max() > S - e:
        return False
    polys = [shapely.Polygon(q) for q in placed]
    tree = shapely.STRtree(polys)
    # (the linear programs hold their separations with equality: a hair of rounding allowed)
    i, j = tree.query(polys, predicate="dwithin", distance=(pm * S + 2 * tol) * (1 - 1e-9))
    return not np.any(i != j)


def on_exact(outlines, exact, placement, side, options, tol):
    """What to compact: the exact outlines (``exact``, before their simplification, in the
    frame of ``outlines``) refitted to their own extent, with ``EXACT_TOL`` tol (at least
    ``ROUNDING`` of the side) as their margin; else (no exact outlines, or they do not keep the
    padding refitted) the layout as given. Returns (outlines, (placement, side), tol)."""
    if exact is not None:
        margin = max(EXACT_TOL * tol, ROUNDING * side)
        start = refitted(exact, placement, options, margin)
        if start is not None:
            return exact, start, margin
    return outlines, (placement, side), tol


def refitted(outlines, placement, options, tol):
    """The layout of other outlines of the same charts (the exact ones in the frame of the
    simplified ones that were placed) moved as one to the low corner, in the square of their
    extent plus the edges: (Placement, side), or None when they do not keep the padding
    there."""
    shift, side = _cornered(outlines, placement, options.padding, tol)
    if not fits(outlines, placement.angle, shift, side, options.padding, options.padding, tol):
        return None
    return Placement(placement.angle, shift, side), side


def anchored(outlines, angle, shift, S, pad, pm, tol):
    """The layout moved as one to the square's low corner and the side cut to its extent, where
    that checks exactly; else (shift, S) as given.

    The programs bound the charts by S alone, so charts the side does not depend on drift
    (their move is any vertex of the program's polytope): with a budget too short to bring them
    back (two charts, 0.1 s: Blender's torus at seed 2 ended 9 % and 7 % of the side from the
    low edges, coverage 0.58 where seed 0 reaches 0.78), the square kept that slack. Moving every
    chart alike keeps their gaps, and a smaller side asks a smaller padding."""
    moved, tight = _cornered(outlines, Placement(angle, shift, S), pad, tol)
    if tight >= S:
        return shift, S
    if not fits(outlines, angle, moved, tight, pad, pm, tol):
        return shift, S
    return moved, tight


def _cornered(outlines, placement, pad, tol):
    """The placement's shifts moved as one so that its outlines start at the low corner of the
    square of their extent plus the edges (padding ``pad`` of the side, and ``tol``), and that
    side: ((k,2) shift, side)."""
    lo, hi = placed_bounds(outlines, placement)
    low = lo.min(axis=0)
    side = (float((hi.max(axis=0) - low).max()) + 2 * tol) / (1 - pad) * (1 + 1e-12)
    return placement.shift - low + (0.5 * pad * side + tol), side
