"""Bijective maps onto a boundary you choose (Lipman 2012, section 5, Theorems 5.1 and 5.2).

An orientation-preserving piecewise-linear map that takes a disk's boundary one-to-one onto a
simple polygon is a bijection onto the polygon's inside (Theorem 5.1), even a non-convex one; with
holes, the outer boundary and every hole must go one-to-one onto the boundary of a domain with as
many holes (Theorem 5.2). ``boundary_targets`` gives target positions for the outer boundary of an
island (circle, rectangle, or the polygon its pins give), which a fixed-boundary BD solve keeps as
pins (``targets.py``); holes stay holes: ``fixed_boundary_map`` fills them for the solve with
triangles held orientation-preserving, so the filled disk maps bijectively (Theorem 5.1) and no
hole crosses the outer boundary (``fixed_map.py``). ``bijectivity.bijectivity_premises`` checks
the premises on the result.
"""
from ..bijectivity import bijectivity_premises, oriented_loop
from .fixed_map import FILL_WEIGHT, HOMOTOPY_STEPS, FixedBoundaryMap, fill_holes, fixed_boundary_map
from .targets import SHAPES, boundary_pins, boundary_targets, check_targets, rectangle_corners

__all__ = ["FILL_WEIGHT", "HOMOTOPY_STEPS", "SHAPES", "FixedBoundaryMap", "bijectivity_premises",
           "boundary_pins", "boundary_targets", "check_targets", "fill_holes",
           "fixed_boundary_map", "oriented_loop", "rectangle_corners"]
