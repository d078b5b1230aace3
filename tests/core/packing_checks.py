"""``check_layout``: everything a packed layout promises, recomputed from its float32 UVs by code
that shares nothing with the packer (exact triangle overlap test, brute-force edge distances,
densities and turns from the corners), then compared with the product's own certificate.
Shared by ``test_packing.py`` and the atlas fuzz contract ``test_fuzz_atlas.py``."""
import numpy as np
import pytest

from bd_uv.packing import layout_certificate
from overlap_shapes import overlapping_triangle_pairs
from packing_sets import chart_maps, least_gap, texel_densities


def check_layout(V, F, uv_in, lab, packed, options, tiles=(1001,), pinned=None):
    """Assert the layout of ``packed`` (charts ``lab`` of the input ``uv_in``) is certified.

    pinned : (k,) bool, optional: these charts keep their input UVs bit for bit; the density and
        the similarity checks then cover the other charts only.

    Returns the product's LayoutCertificate (certified).
    """
    out = packed.corner_uv.astype(np.float32).astype(np.float64)
    res, pad = options.resolution, options.padding_px
    keep = np.zeros(len(lab), bool) if pinned is None else np.asarray(pinned, bool)[lab]
    assert np.array_equal(packed.corner_uv[keep], uv_in[keep])      # pinned: bit for bit
    # inside its tile, half the padding from the edge
    t = packed.tile[lab] - 1001
    lo = np.stack([t % 10, t // 10], 1)[:, None, :]
    assert np.all(out >= lo + 0.5 * pad / res * (1 - 1e-3))
    assert np.all(out <= lo + 1 - 0.5 * pad / res * (1 - 1e-3))
    assert sorted(set(packed.tile.tolist())) == list(tiles)
    # no overlap: every pair of triangles of different charts is separated (exact SAT test)
    pairs = overlapping_triangle_pairs(out)
    assert not np.any(lab[pairs[:, 0]] != lab[pairs[:, 1]])
    # least gap between two charts >= padding, measured at the resolution
    # (within each tile: UDIM tiles are separate textures, so charts in two tiles have no gap to
    # keep; the certificate measures them so too)
    face_tile = packed.tile[lab]
    gap = min((least_gap(out[face_tile == t], lab[face_tile == t], reach=2 * pad / res + 1e-9)
               for t in np.unique(face_tile)), default=np.inf) * res
    assert gap >= pad * (1 - 1e-4) or (pad == 0 and gap > 0)
    # one density: sqrt(UV area / 3D area) equal for every chart that moved (float32 rounding
    # moves tiny charts' areas by up to about 1e-4)
    moved = np.unique(lab[~keep])
    if len(moved):
        d = texel_densities(V, F, packed.corner_uv, lab)[moved]
        assert np.allclose(d, d[0], rtol=1e-9)
        # as stored: rounding a corner by half the float32 spacing at the chart's coordinates
        # (6e-8 near 1, 5e-7 near 5 in a far UDIM tile) moves a triangle's area by at most
        # spacing / h of it (h its least height), the chart's density by no more than its
        # thinnest triangle's (a sliver 4e-5 high in tile 1006: 1.8e-3, found at 2,000 deep)
        d32 = texel_densities(V, F, out, lab)[moved]
        tol = []
        for c in moved:   # per chart
            u = out[lab == c]
            e = np.stack([u[:, 1] - u[:, 0], u[:, 2] - u[:, 1], u[:, 0] - u[:, 2]], axis=1)
            area2 = np.abs(e[:, 0, 0] * e[:, 2, 1] - e[:, 0, 1] * e[:, 2, 0])
            h = area2 / np.linalg.norm(e, axis=2).max(axis=1)
            step = float(np.spacing(np.float32(np.abs(u).max())))
            tol.append(1e-3 + 2 * step / max(h.min(), 1e-30))
        assert np.all(np.abs(d32 / d[0] - 1) <= np.array(tol))
        assert np.isclose(d[0] * res, packed.texel_density, rtol=1e-5)
        # a turn and a scale per face, never a mirror: J = s R with det > 0 (no flip as stored:
        # float32; the similarity from float64, float32 rounding of thin slivers aside)
        # A face thinner than float32's step at its place in the texture cannot keep its shape
        # as stored, wherever a similarity puts it (a sliver 1e-8 across at res 64, seed 7373 at
        # 300 deep): it may collapse or flip there only, and the certificate must say so (below).
        det = np.linalg.det(chart_maps(uv_in[~keep], out[~keep]))
        if np.any(det <= 0):
            q = packed.corner_uv[~keep][det <= 0]
            e = np.stack([q[:, 1] - q[:, 0], q[:, 2] - q[:, 1], q[:, 0] - q[:, 2]], axis=1)
            twice = np.abs(e[:, 0, 0] * e[:, 2, 1] - e[:, 0, 1] * e[:, 2, 0])
            height = twice / np.linalg.norm(e, axis=2).max(axis=1)
            step = np.spacing(np.abs(q).max(axis=(1, 2)).astype(np.float32)).astype(np.float64)
            assert np.all(height < 4 * step), "a face float32 can hold flipped as stored"
        J = chart_maps(uv_in[~keep], packed.corner_uv[~keep])
        assert np.allclose(J[:, 0, 0], J[:, 1, 1], atol=1e-4 * np.abs(J).max())
        assert np.allclose(J[:, 0, 1], -J[:, 1, 0], atol=1e-4 * np.abs(J).max())
        if options.rotate == "none":
            assert np.allclose(J[:, 0, 1], 0, atol=1e-5 * np.abs(J).max())
    # the product's own certificate agrees with the independent figures
    cert = layout_certificate(V, F, out.astype(np.float32), lab, packed.tile, res, pad)
    # every face turns counter-clockwise as the charts came (pack_islands refuses others), but a
    # face float32 cannot hold (above): then the certificate says so, and for that alone
    P = out[lab >= 0]
    twice = ((P[:, 1, 0] - P[:, 0, 0]) * (P[:, 2, 1] - P[:, 0, 1])
             - (P[:, 1, 1] - P[:, 0, 1]) * (P[:, 2, 0] - P[:, 0, 0]))
    flips = int(np.sum(~(twice > 0)))
    assert cert.flipped_faces == flips
    if flips:
        assert not cert.certified and cert.reason.startswith(f"{flips} face(s) flipped"), \
            cert.reason
    else:
        assert cert.certified, cert.reason
    reach_px = 2 * pad + 1e-9 * res
    if gap <= reach_px:       # least_gap is exact within its reach
        assert cert.least_gap_px == pytest.approx(gap, rel=1e-6)
    elif np.isfinite(gap):    # beyond it, an upper bound of the least gap (nearby pairs only)
        assert reach_px * (1 - 1e-6) <= cert.least_gap_px <= gap * (1 + 1e-6)
    if pinned is None and len(moved):
        # the spread as stored, recomputed here (float32 keeps tiny charts in far tiles' within
        # the per-chart bound above only: 1.0013 for a chart 4e-4 wide in tile 1010)
        assert cert.density_spread == pytest.approx(d32.max() / d32.min(), rel=1e-9)
    return cert


def placed(outlines, angle, shift):
    """Each outline (n_i,2) turned by its angle in degrees and moved by its shift, computed here."""
    out = []
    for xy, a, t in zip(outlines, angle, shift):  # per chart
        r = np.deg2rad(a)
        R = np.array([[np.cos(r), -np.sin(r)], [np.sin(r), np.cos(r)]])
        out.append(xy @ R.T + t)
    return out


def inside(p, ring):
    """Even-odd test: is point p strictly inside the closed ring (n,2)?"""
    a, b = ring, np.roll(ring, -1, axis=0)
    cross = (a[:, 1] > p[1]) != (b[:, 1] > p[1])
    x = a[:, 0] + (p[1] - a[:, 1]) * (b[:, 0] - a[:, 0]) / np.where(cross, b[:, 1] - a[:, 1], 1)
    return bool(np.sum(cross & (x > p[0])) % 2)


def check_reach_asked(monkeypatch, V, F, uv, lab, reach):
    """pack_islands asks square_layout for ``reach`` with the adaptive time (each solve asked
    to end at its square) and for 1 with a time given (no solve asked to end); the layouts
    certified."""
    import bd_uv.packing.atlas as atlas
    import bd_uv.packing.square as square
    from bd_uv.packing import PackOptions, pack_islands
    seen, ends = [], []
    real, solve_all = atlas.square_layout, square._solve_all
    monkeypatch.setattr(atlas, "square_layout",
                        lambda *a, **kw: seen.append(kw.get("reach")) or real(*a, **kw))
    monkeypatch.setattr(square, "_solve_all",
                        lambda *a, **kw: ends.append(kw.get("square")) or solve_all(*a, **kw))
    for solve in (None, 0.3):
        options = PackOptions(seed=0, solve_seconds=solve)
        seen.clear()
        ends.clear()
        check_layout(V, F, uv, lab, pack_islands(V, F, uv, lab, options), options)
        assert seen == [reach if solve is None else 1.0]
        assert ends and ends[0] is (True if solve is None else None)


def check_no_reach_on_a_thread(monkeypatch, V, F, uv, lab):
    """Packed on a worker thread (Blender's operator, a Dask worker), where a search cannot be
    ended early: pack_islands asks for no reach; the layout certified."""
    import threading

    import bd_uv.packing.atlas as atlas
    from bd_uv.packing import PackOptions, pack_islands
    seen = []
    real = atlas.square_layout
    monkeypatch.setattr(atlas, "square_layout",
                        lambda *a, **kw: seen.append(kw.get("reach")) or real(*a, **kw))
    options, out = PackOptions(seed=0), []
    t = threading.Thread(target=lambda: out.append(pack_islands(V, F, uv, lab, options)))
    t.start()
    t.join()
    assert seen == [1.0]
    check_layout(V, F, uv, lab, out[0], options)
