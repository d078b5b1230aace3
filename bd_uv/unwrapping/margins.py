"""How far inside a requested bound a map is solved, so that its certificate passes on the UVs as
stored: ``solve_bound`` (the C a solve uses), ``STORE_HEADROOM`` (what a certified bound keeps
above a map's float64 distortion, for float32 and packed UVs), ``certified_bound`` (the bound
reported for a map of a given max distortion) and the margin of a solve's singular-value bounds
under a stretch limit S (``STRETCH_MARGIN_SOLVE``)."""
import math

SOLVE_MARGIN = 2e-3      # solve at a C slightly below the bound so certification has headroom
# Relative headroom a certified bound keeps above the map's float64 distortion, so that the UVs
# still pass when stored as float32 (Blender) or packed into the unit square.
STORE_HEADROOM = 2e-4


def solve_bound(C):
    """The C a solve uses for a requested bound C: a little below it (SOLVE_MARGIN on C - 1, and
    STORE_HEADROOM relative), never below 1."""
    return max(1.0, min(1.0 + (C - 1.0) * (1.0 - SOLVE_MARGIN), C / (1.0 + STORE_HEADROOM)))


# With stretch bounds (section 6.3) a conic solve bounds the singular values by [m/S, S/m] at the
# held scale, first with this m (``stretch.stretch_solve`` grows it when the result misses).
STRETCH_MARGIN_SOLVE = 1.005


def certified_bound(max_distortion, headroom=STORE_HEADROOM):
    """The bound ``bound="auto"`` reports for a map: its max distortion with ``headroom``
    (STORE_HEADROOM), with C - 1 rounded up to 4 significant digits (1.03633 for 1.036117, 3.858
    for 3.8563), so the UVs still pass as stored (float32, packed) and a C close to 1 keeps the
    precision it was minimised to (the search's tolerance is relative to C - 1 too).
    ``rounding.tightened`` lowers it where the rounding's own bound is below the headroom."""
    c = max_distortion * (1.0 + headroom)
    excess = c - 1.0
    if not excess > 0.0:
        return c
    digits = 3 - int(math.floor(math.log10(excess)))
    return 1.0 + math.ceil(excess * 10 ** digits) / 10 ** digits
