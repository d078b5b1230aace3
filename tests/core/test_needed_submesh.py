"""``seams.needed.island_submesh``: the islands sent to the seam search joined on their own cut
vertices, so islands meeting only at a vertex (where a certified island lay between them) are
no bow-tie, a seam inside an island stays open, and every face keeps its vertices."""
import numpy as np

from bd_uv.mesh import islands
from bd_uv.seams.needed import island_submesh


def fan(k=6):
    """A closed fan of k triangles round vertex 0 (a disk), lifted off the plane."""
    t = 2 * np.pi * np.arange(k) / k
    V = np.r_[[[0.0, 0.0, 0.3]], np.c_[np.cos(t), np.sin(t), np.zeros(k)]]
    F = np.array([[0, 1 + i, 1 + (i + 1) % k] for i in range(k)], dtype=np.int64)
    return V, F


def two_rings(k=6):
    """``fan`` with a second ring of quads (two triangles each) round it: vertices 1..k inner,
    k+1..2k outer; faces 0..k-1 the fan."""
    V, F = fan(k)
    t = 2 * np.pi * np.arange(k) / k
    V = np.r_[V, np.c_[2 * np.cos(t), 2 * np.sin(t), np.zeros(k)]]
    i = np.arange(k)
    a, b, c, d = 1 + i, 1 + (i + 1) % k, 1 + k + (i + 1) % k, 1 + k + i
    return V, np.r_[F, np.c_[a, d, c], np.c_[a, c, b]].astype(np.int64)


def test_an_island_round_a_vertex_with_another_between_is_no_bow_tie():
    """Fan faces 0 and 3 are islands of their own (seams round them); the rest is one island
    going round vertex 0 through the outer ring, its corners at vertex 0 in two groups. Alone,
    on the mesh's vertex ids, those two groups meet only at vertex 0: a bow-tie (usd-wg's chess
    pawn). On the island's cut vertices they are two vertices."""
    V, F = two_rings()
    seams = np.array([[0, 1], [0, 2], [1, 2], [0, 4], [0, 5], [4, 5]])
    isl = islands(V, F, seams)
    big = next(i for i in isl if len(i.faces) == len(F) - 2)
    assert big.error is None
    sub, voc, Fl = island_submesh(F, [big])
    assert np.array_equal(sub, np.sort(big.faces))
    assert np.array_equal(voc[Fl], F[sub])        # each face keeps its vertices
    assert np.count_nonzero(voc == 0) == 2        # vertex 0 twice: one per group of corners
    assert [i.error for i in islands(V[voc], Fl)] == [None]   # the search's own check
    # the mesh's vertex ids instead (the old way): refused as a bow-tie at vertex 0
    old_voc, old_F = np.unique(F[sub], return_inverse=True)
    bad = islands(V[old_voc], old_F.reshape(-1, 3))
    assert len(bad) == 1 and "non-manifold vertex" in str(bad[0].error)


def test_a_seam_inside_an_island_stays_open_and_one_island_keeps_its_order():
    V, F = fan()
    whole = islands(V, F)[0]
    sub, voc, Fl = island_submesh(F, [whole])
    # one island with no seam: the faces and vertices as np.unique gives them
    u, inv = np.unique(F, return_inverse=True)
    assert np.array_equal(sub, np.arange(6)) and np.array_equal(voc, u)
    assert np.array_equal(Fl, inv.reshape(-1, 3))
    slit = islands(V, F, np.array([[0, 1]]))[0]    # one spoke cut: a slit into the disk
    sub, voc, Fl = island_submesh(F, [slit])
    assert np.array_equal(voc[Fl], F) and np.bincount(voc)[1] == 2   # vertex 1 on both sides
    assert islands(V[voc], Fl)[0].error is None and len(islands(V[voc], Fl)[0].loops) == 1
