"""Mesh preparation: validate, cut along seams, split into islands.

- ``arrays``: the arrays checked (shapes, indices, numbers), coordinates too large to measure,
  faces too thin for the stored precision;
- ``islands``: the mesh cut along seams into islands, each with its cut vertices, triangles and
  boundary loops, or why it cannot be parameterized;
- ``faults``: that reason, in the user's terms (faces and vertices named).
"""
from .arrays import (DEGENERATE_RATIO, MEASURABLE, TOO_LARGE, as_indices, as_reals,
                     check_arrays, measurable, thinner_than_precision)
from .islands import Island, checked_islands, islands

__all__ = ["DEGENERATE_RATIO", "MEASURABLE", "TOO_LARGE", "Island", "as_indices", "as_reals",
           "check_arrays", "checked_islands", "islands", "measurable", "thinner_than_precision"]
