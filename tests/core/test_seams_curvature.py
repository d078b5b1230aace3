"""The curvature that lets the seam search split a chart without mapping it (``rounds.CURVED``,
``rounds.PIECE_CURVED``): each vertex's angle defect and each face's share, checked against
Gauss-Bonnet and against corner angles recomputed here with ``arccos``; and a large closed
sphere whose curved charts are split unmapped still ends in certified charts."""
import numpy as np

from bd_uv.seams import rounds, unwrap_auto
from bd_uv.seams.topology import charts as seam_charts
from bd_uv.geometry import face_areas
from bd_uv.seams.edges import edge_table

from helpers import grid
from seams_helpers import torus, uv_sphere
from test_seams import C, S, check_charts


def _defects(V, F):
    """2 pi minus each vertex's corner angles by arccos of normalised edge vectors."""
    total = np.zeros(len(V))
    for k in range(3):
        a = V[F[:, (k + 1) % 3]] - V[F[:, k]]
        b = V[F[:, (k + 2) % 3]] - V[F[:, k]]
        cos = (a * b).sum(1) / (np.linalg.norm(a, axis=1) * np.linalg.norm(b, axis=1))
        np.add.at(total, F[:, k], np.arccos(np.clip(cos, -1, 1)))
    return 2 * np.pi - total


def test_a_closed_meshs_defects_sum_to_2_pi_times_its_euler_characteristic(monkeypatch):
    V, F, _ = uv_sphere(24, 12)
    assert len(F) < rounds.CURVED_FACES      # no chart large enough: nothing formed
    assert rounds.angle_defects(V, F, edge_table(V, F), face_areas(V, F)) is None
    monkeypatch.setattr(rounds, "CURVED_FACES", 0)
    for (V, F), chi in (((uv_sphere(24, 12)[:2]), 2), (torus()[:2], 0)):
        defect, share = rounds.angle_defects(V, F, edge_table(V, F), face_areas(V, F))
        assert defect.shape == (len(V),) and share.shape == (len(F),)
        assert abs(defect.sum() - 2 * np.pi * chi) < 1e-9
        assert abs(share.sum() - 2 * np.pi * chi) < 1e-9
        assert np.allclose(defect, _defects(V, F), atol=1e-9)


def test_boundary_vertices_have_no_defect_and_a_flat_grid_none_at_all(monkeypatch):
    monkeypatch.setattr(rounds, "CURVED_FACES", 0)
    V, F = grid(7, 6)
    defect, share = rounds.angle_defects(V, F, edge_table(V, F), face_areas(V, F))
    assert np.abs(defect).max() < 1e-12 and np.abs(share).max() < 1e-12
    V, F = grid(7, 6, z=lambda x, y: 0.3 * np.sin(3 * x) * np.cos(2 * y))
    E = edge_table(V, F)
    defect, _ = rounds.angle_defects(V, F, E, face_areas(V, F))
    border = np.unique(E.ends[E.faces[:, 1] < 0])
    inner = np.setdiff1d(np.arange(len(V)), border)
    assert np.all(defect[border] == 0)
    assert np.allclose(defect[inner], _defects(V, F)[inner], atol=1e-9)
    assert np.abs(defect[inner]).max() > 1e-3


def test_a_caps_curvature_is_its_interior_vertices_defects(monkeypatch):
    monkeypatch.setattr(rounds, "CURVED_FACES", 0)
    V, F, _ = uv_sphere(24, 12)
    E = edge_table(V, F)
    defect, _ = rounds.angle_defects(V, F, E, face_areas(V, F))
    north = np.flatnonzero(V[F].mean(axis=1)[:, 2] > 0.5)
    cut = np.zeros(len(E.ends), dtype=bool)
    inner = E.faces[:, 1] >= 0
    side = np.isin(E.faces[:, 0], north) != np.isin(E.faces[:, 1], north)
    cut[inner & side] = True
    (cap,) = [c for c in seam_charts(F, E, cut) if np.isin(c.faces, north).all()]
    assert cap.kind == "disk"
    ring = np.unique(F[north])
    ring = ring[V[ring, 2] <= V[ring, 2].min() + 1e-12]     # the cap's boundary loop
    interior = np.setdiff1d(np.unique(F[north]), ring)
    assert abs(rounds.curvature(cap, defect) - _defects(V, F)[interior].sum()) < 1e-9


def test_a_large_sphere_maps_no_chart_curved_beyond_the_limits(monkeypatch):
    # The closed sphere is split unmapped, and its pieces again while curved beyond
    # PIECE_CURVED: the first maps are of pieces within it; no chart of CURVED_FACES faces or
    # more curved beyond CURVED is ever mapped; every chart is certified.
    V, F, _ = uv_sphere(96, 48)
    assert len(F) >= 2 * rounds.CURVED_FACES
    batches = []
    solve = rounds.chart_maps

    def record(V_, chs, *a, **k):
        batches.append(list(chs))
        return solve(V_, chs, *a, **k)
    monkeypatch.setattr(rounds, "chart_maps", record)
    res, _, info = unwrap_auto(V, F, bound=C, stretch=S)
    check_charts(V, F, res)
    exact = _defects(V, F)
    assert batches
    for c in batches[0]:
        if len(c.faces) >= rounds.CURVED_FACES:
            assert _share(V, F, exact)[c.faces].sum() <= rounds.PIECE_CURVED + 1e-9
    for c in (c for b in batches for c in b):
        if len(c.faces) >= rounds.CURVED_FACES:
            inside = np.setdiff1d(np.arange(len(c.vertices)), c.loops[0])
            assert exact[c.vertices[inside]].sum() <= rounds.CURVED + 1e-9


def _share(V, F, defect):
    """Each face's share of its corners' vertex defects, by the corners' angles (arccos)."""
    ang = np.empty(F.shape)
    for k in range(3):
        a = V[F[:, (k + 1) % 3]] - V[F[:, k]]
        b = V[F[:, (k + 2) % 3]] - V[F[:, k]]
        cos = (a * b).sum(1) / (np.linalg.norm(a, axis=1) * np.linalg.norm(b, axis=1))
        ang[:, k] = np.arccos(np.clip(cos, -1, 1))
    total = np.zeros(len(V))
    np.add.at(total, F, ang)
    return (ang * (defect / total)[F]).sum(1)
