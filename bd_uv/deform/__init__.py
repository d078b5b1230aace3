"""Planar deformation with handles within a conformal bound (Lipman 2012, section 6.1): the
certified ``deform`` of a planar mesh or UV layout (``planar.py``) and the solve over F_C with
vertices held fixed, with frame resets (eq. 4.21), that it, ``boundary.fixed_boundary_map`` and
``improve`` share (``handles.py``).
"""
from .handles import (IMPROVEMENT, LOOSE_BOUND, MAX_RESETS, MAX_RETRIES, METHODS, SOLVE_MARGIN,
                      alpha_of, bounded_with_resets, energy_value, map_distortion,
                      planar_operators, solve_with_handles)
from .planar import DeformResult, deform

__all__ = ["DeformResult", "IMPROVEMENT", "LOOSE_BOUND", "MAX_RESETS", "MAX_RETRIES", "METHODS",
           "SOLVE_MARGIN", "alpha_of", "bounded_with_resets", "deform", "energy_value",
           "map_distortion", "planar_operators", "solve_with_handles"]
