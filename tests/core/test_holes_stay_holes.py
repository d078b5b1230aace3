"""Holes stay holes with a fixed outer boundary (Lipman 2012, section 5): each hole is filled for
the solve by triangles held orientation-preserving, so the filled disk maps bijectively onto the
target polygon (Theorem 5.1) and no hole can be pushed through the outer boundary. Checked here
without bd_uv's metrics: SVD of each face's map, every pair of UV triangles for overlap, the hole's
image inside the square."""
import numpy as np

import bd_uv
from helpers import reference_distortion
from overlap_shapes import overlapping_triangle_pairs
from planar import boundary_edges, circle, mesh_polygon


def strip_with_a_hole():
    """A 4 x 1 strip with a hole of radius 0.25 close to its top edge (Triangle): (V (n,3), F,
    the four corner vertices)."""
    xs = np.linspace(0.0, 4.0, 40, endpoint=False)
    ys = np.linspace(0.0, 1.0, 10, endpoint=False)
    outer = np.concatenate([np.c_[xs, 0 * xs], np.c_[4 + 0 * ys, ys], np.c_[4 - xs, 1 + 0 * xs],
                            np.c_[0 * ys, 1 - ys]])
    V2, F = mesh_polygon(outer, [circle(16, 0.25, (3.5, 0.68))[::-1]], [[3.5, 0.68]], area=0.01)
    corners = [int(np.argmin(np.linalg.norm(V2 - p, axis=1))) for p in [(0, 0), (4, 0), (4, 1),
                                                                        (0, 1)]]
    return np.c_[V2, np.zeros(len(V2))], F, np.array(corners)


def test_a_strip_mapped_to_a_square_keeps_its_hole_inside():
    """Squeezing the strip into a 2 x 2 square pushed the hole (free) through the top side
    before; now the island is bijective with 0 overlapping triangle pairs."""
    V, F, corners = strip_with_a_hole()
    pin_corners = np.array([3 * f + k for f, k in (np.argwhere(F == v)[0] for v in corners)])
    square = np.array([[0.0, 0.0], [2.0, 0.0], [2.0, 2.0], [0.0, 2.0]])
    for C in (5.0, 20.0):
        res = bd_uv.unwrap(V, F, boundary="pinned", bound=C, pin_corners=pin_corners,
                           pin_uv=square, overlap="fail")
        (isl,) = res.islands
        assert isl.status == "certified" and isl.bijective is True, isl.message
        D, flipped = reference_distortion(V, F, res.corner_uv)
        assert flipped.sum() == 0 and D.max() <= C * (1 + 1e-6)
        assert len(overlapping_triangle_pairs(res.corner_uv)) == 0
        uv = np.full((len(V), 2), np.nan)
        uv[F.ravel()] = res.corner_uv.reshape(-1, 2)
        b = np.unique(boundary_edges(F))
        hole = b[np.linalg.norm(V[b, :2] - [3.5, 0.68], axis=1) < 0.3]
        assert len(hole) == 16
        assert np.all((uv[hole] > 0) & (uv[hole] < 2))   # strictly inside the square
        assert np.allclose(uv[corners], square, rtol=0, atol=0)
