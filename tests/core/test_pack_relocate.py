"""bd_uv.packing.relocate: a small chart bounding the square moved into the free space deepest
inside it, checked by code that shares nothing with it (brute-force segment distances, an
even-odd point-in-polygon test, the placed outlines recomputed from the angles and shifts)."""
import numpy as np

from bd_uv.packing import PackOptions
from bd_uv.packing.relocate import relocate
from packing_checks import inside, placed
from packing_sets import segment_distances

# a U of 8 x 8 in a square of side 12, its pocket 4 wide and 6 deep open to the top, and a
# 1 x 1 box against the square's right edge as close to it as the U is to the left one
U = np.array([[-4.0, -4.0], [4.0, -4.0], [4.0, 4.0], [2.0, 4.0], [2.0, -2.0], [-2.0, -2.0],
              [-2.0, 4.0], [-4.0, 4.0]])
BOX = 0.5 * np.array([[-1.0, -1.0], [1.0, -1.0], [1.0, 1.0], [-1.0, 1.0]])
SIDE = 12.0
SEP = 0.2


def _gap(a, b):
    a0, a1, b0, b1 = a, np.roll(a, -1, axis=0), b, np.roll(b, -1, axis=0)
    I, J = np.meshgrid(np.arange(len(a)), np.arange(len(b)), indexing="ij")
    I, J = I.ravel(), J.ravel()
    return float(segment_distances(a0[I], a1[I], b0[J], b1[J]).min())


def _depth(ring):
    return float(min(ring.min(), SIDE - ring.max()))


def test_a_small_chart_against_the_edge_goes_into_the_pocket():
    """The box leaves the right edge for the U's pocket: deeper inside the square than before,
    the separation from the U kept (brute force), not inside the U, inside the square with half
    the separation; the box only turned by quarter turns (its ring's distances kept), the U
    left as it was."""
    angle = np.array([0.0, 0.0])
    shift = np.array([[4.5, 4.5], [11.0, 6.0]])
    before = placed([U, BOX], angle, shift)
    assert np.isclose(_depth(before[0]), _depth(before[1]))   # both bound the square
    a2, s2, moved = relocate([U, BOX], angle, shift, SIDE, SEP, PackOptions(rotate="any"))
    assert moved == 1
    assert a2[0] == 0.0 and np.array_equal(s2[0], shift[0])
    u, box = placed([U, BOX], a2, s2)
    assert _depth(box) > _depth(before[1]) + 1.0
    assert _gap(u, box) >= SEP
    assert not inside(box[0], u) and not inside(u[0], box)
    assert box.min() >= 0.5 * SEP and box.max() <= SIDE - 0.5 * SEP
    # in the pocket: between its walls and below its opening
    assert (box[:, 0] > 2.5).all() and (box[:, 0] < 6.5).all() and (box[:, 1] < 8.5).all()
    assert np.isclose((a2[1] - angle[1]) % 90.0, 0.0) or np.isclose((a2[1] - angle[1]) % 90.0,
                                                                    90.0)
    assert np.allclose(np.linalg.norm(box[1:] - box[0], axis=1),
                       np.linalg.norm(BOX[1:] - BOX[0], axis=1), rtol=1e-12)


def test_no_chart_moves_when_only_a_large_one_bounds_the_square():
    """The box well inside the square (not against an edge): nothing moves, the arrays come
    back equal; with rotate "none" a bounding box may move but never turns."""
    angle = np.array([0.0, 0.0])
    shift = np.array([[4.5, 4.5], [10.0, 6.0]])
    a2, s2, moved = relocate([U, BOX], angle, shift, SIDE, SEP, PackOptions())
    assert moved == 0 and np.array_equal(a2, angle) and np.array_equal(s2, shift)
    shift = np.array([[4.5, 4.5], [11.0, 6.0]])
    a2, s2, moved = relocate([U, BOX], angle, shift, SIDE, SEP, PackOptions(rotate="none"))
    assert moved == 1 and np.array_equal(a2, angle)
    u, box = placed([U, BOX], a2, s2)
    assert _gap(u, box) >= SEP and _depth(box) > 1.5
