"""bd_uv: certified bounded-distortion UV parameterization (Lipman 2012), without Blender.

>>> import bd_uv
>>> res = bd_uv.unwrap(V, F, bound=5.0)          # doctest: +SKIP
>>> res.corner_uv, [r.max_distortion for r in res.islands]   # doctest: +SKIP
"""
from .bijectivity import bijectivity_premises
from .boundary import boundary_pins, boundary_targets, fixed_boundary_map
from .certificate import Certificate, certificate_totals, certify_islands
from .colors import distortion_colors
from .deform import DeformResult, deform
from .errors import (BDError, CancelledError, ClosedIslandError, DegenerateFacesError,
                     DuplicateFacesError, InfeasibleError, InvalidMeshError, IslandError,
                     NonFiniteError, NonManifoldError, OptionError, OrientationError,
                     OverlapError, SolverError, TopologyError)
from .improve import ImproveResult, equilateral_distortion, improve
from .live import LiveFrame, LiveSession, SessionClosedError
from .metrics import (certify, conformal_distortion, face_jacobians, flipped_faces,
                      mean_distortion, signed_uv_areas, singular_values)
from .mesh import Island, islands
from .overlap import island_overlaps, layout_overlaps
from . import packing
from .packing import PackOptions, layout_certificate, pack_islands
from .meshio import Mesh, load_mesh, write_obj
from .options import UnwrapOptions
from .api import unwrap
from .unwrapping import IslandResult, UnwrapResult

__version__ = "0.1.0"
