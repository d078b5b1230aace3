"""uv.bd_unwrap on an island whose UVs would lie over themselves (issue 10): with Overlaps "Cut
Into Pieces" and Marked seams the island comes back as overlap-free pieces and the cut edges are
marked as seams (one undo step takes both back); with Add Where Needed (the default) its charts
come from the seam search instead, their seams marked; with "Keep as One Island" nothing is
written and the report names the island. Distortion and overlap are checked here independently of bd_uv."""
import numpy as np
from conftest import bpy, loop_uv_array, set_mode, triangle_distortion


def add_helicoid_ribbon(turns=2.2, n_around=110, n_across=2, r0=0.3, r1=1.0, pitch=0.35):
    """A ribbon of quads winding 2.2 times round an axis: its conformal map spirals over itself."""
    th = np.linspace(0, 2 * np.pi * turns, n_around + 1)
    r = np.linspace(r0, r1, n_across + 1)
    T, R = np.meshgrid(th, r, indexing="ij")
    V = np.stack([R * np.cos(T), R * np.sin(T), pitch * T], -1).reshape(-1, 3)
    a = (np.arange(n_around)[:, None] * (n_across + 1) + np.arange(n_across)[None, :]).ravel()
    quads = np.stack([a, a + n_across + 1, a + n_across + 2, a + 1], 1)
    mesh = bpy.data.meshes.new("Ribbon")
    mesh.from_pydata(V.tolist(), [], quads.tolist())
    mesh.uv_layers.new(name="UVMap")
    obj = bpy.data.objects.new("Ribbon", mesh)
    bpy.context.collection.objects.link(obj)
    return obj


def seams(mesh):
    s = np.zeros(len(mesh.edges), bool)
    mesh.edges.foreach_get("use_seam", s)
    return s


def tri_arrays(mesh):
    mesh.calc_loop_triangles()
    V = np.array([v.co[:] for v in mesh.vertices])
    tris = np.array([t.vertices[:] for t in mesh.loop_triangles])
    loops = np.array([t.loops[:] for t in mesh.loop_triangles])
    return V, tris, loops


def segments_cross(a, b, c, d):
    """Proper crossing of segments ab and cd (2D)."""
    def orient(p, q, r):
        return np.sign((q[0] - p[0]) * (r[1] - p[1]) - (q[1] - p[1]) * (r[0] - p[0]))
    return (orient(a, b, c) * orient(a, b, d) < 0) and (orient(c, d, a) * orient(c, d, b) < 0)


def overlapping_triangles(uv):
    """Pairs of UV triangles whose edges cross properly (a brute-force, bd_uv-free test)."""
    lo, hi = uv.min(axis=1), uv.max(axis=1)
    hits = 0
    for i in range(len(uv)):
        cand = np.flatnonzero(np.all(lo[i] < hi, axis=1) & np.all(lo < hi[i], axis=1))
        for j in cand[cand > i]:
            if any(segments_cross(uv[i][e], uv[i][(e + 1) % 3], uv[j][f], uv[j][(f + 1) % 3])
                   for e in range(3) for f in range(3)):
                hits += 1
    return hits


def _unwrap_ribbon(capsys, bound, **options):
    """The ribbon unwrapped (Overlaps Cut Into Pieces, packed) after an undo step: its mesh, the
    operator's printed report, the UVs before, and each triangle's distortion and determinant
    and its UVs as stored (checked: flip-free, within ``bound``, no two triangles crossing)."""
    obj = add_helicoid_ribbon()
    set_mode(obj, 'EDIT')
    bpy.ops.mesh.select_all(action='SELECT')
    bpy.ops.ed.undo_push(message="before")
    set_mode(obj, 'OBJECT')
    before_uv = loop_uv_array(obj.data).copy()
    assert not seams(obj.data).any()
    set_mode(obj, 'EDIT')
    assert bpy.ops.uv.bd_unwrap('EXEC_DEFAULT', True, bound=5.0, overlap='CUT', pack=True,
                                **options) == {'FINISHED'}
    out = capsys.readouterr().out
    set_mode(obj, 'OBJECT')
    V, tris, loops = tri_arrays(obj.data)
    uv = loop_uv_array(obj.data).astype(np.float64)[loops]
    D, det = triangle_distortion(V, tris, uv)
    assert (det > 0).all() and D.max() <= bound * (1 + 1e-4)
    assert overlapping_triangles(uv) == 0
    return obj, out, before_uv


def _undo_takes_both_back(obj, before_uv):
    """One undo step takes back the UVs and the seams."""
    set_mode(obj, 'EDIT')
    bpy.ops.ed.undo()
    set_mode(obj, 'OBJECT')
    obj = bpy.data.objects["Ribbon"]
    assert not seams(obj.data).any()
    assert np.array_equal(loop_uv_array(obj.data), before_uv)


def test_cut_into_pieces_marks_the_cut_as_seams_and_undo_takes_both_back(addon, capsys):
    obj, out, before_uv = _unwrap_ribbon(capsys, 5.0, seams='MARKED')
    mesh = obj.data
    marked = seams(mesh)
    assert marked.any() and "marked where overlapping islands were cut" in out, out
    # every marked edge is a real cut: the UVs on its two sides differ
    edge_keys = {tuple(sorted(e.vertices)) for e, m in zip(mesh.edges, marked) if m}
    assert all(k in {tuple(sorted(e.vertices)) for e in mesh.edges} for k in edge_keys)
    _undo_takes_both_back(obj, before_uv)


def test_add_where_needed_gives_an_overlapping_island_the_searchs_charts(addon, capsys):
    """The default seams (Add Where Needed): the ribbon's island, whose map lies over itself,
    is not cut along whatever edges separate the overlap but given charts by the seam search
    (certified at C = 2), their seams marked; one undo step takes back UVs and seams."""
    obj, out, before_uv = _unwrap_ribbon(capsys, 2.0)
    assert seams(obj.data).any() and "seams added" in out and "were cut" not in out, out
    _undo_takes_both_back(obj, before_uv)


def test_keep_as_one_island_writes_nothing_and_names_it(addon, capsys):
    obj = add_helicoid_ribbon()
    set_mode(obj, 'OBJECT')
    before_uv = loop_uv_array(obj.data).copy()
    set_mode(obj, 'EDIT')
    bpy.ops.mesh.select_all(action='SELECT')
    result = bpy.ops.uv.bd_unwrap('EXEC_DEFAULT', bound=5.0, overlap='KEEP')
    out = capsys.readouterr().out
    assert result == {'CANCELLED'}
    assert "lie over themselves" in out, out
    set_mode(obj, 'OBJECT')
    assert np.array_equal(loop_uv_array(obj.data), before_uv)
    assert not seams(obj.data).any()


def test_boundary_circle_puts_the_outer_boundary_on_a_circle(addon):
    """Boundary "Circle" (issue 12, section 5): every boundary vertex's UV on one circle, no
    flipped face, distortion within C, no overlapping triangles."""
    from conftest import add_grid
    obj = add_grid(8, 6)
    set_mode(obj, 'EDIT')
    bpy.ops.mesh.select_all(action='SELECT')
    assert bpy.ops.uv.bd_unwrap('EXEC_DEFAULT', bound=5.0, boundary='circle',
                                pack=False) == {'FINISHED'}
    set_mode(obj, 'OBJECT')
    mesh = obj.data
    V, tris, loops = tri_arrays(mesh)
    uv = loop_uv_array(mesh).astype(np.float64)
    D, det = triangle_distortion(V, tris, uv[loops])
    # The square's corner faces lie on the circle with all three corners: their distortion is
    # forced, so C is raised to it and the report says so.
    last = bpy.context.window_manager.bd_uv_last_result
    assert (det > 0).all() and D.max() <= last.bound_certified * (1 + 1e-4)
    assert overlapping_triangles(uv[loops]) == 0
    count = {}
    for e in mesh.edges:
        count[tuple(sorted(e.vertices))] = 0
    for p in mesh.polygons:
        for k in p.edge_keys:
            count[tuple(sorted(k))] += 1
    boundary = {v for k, c in count.items() if c == 1 for v in k}
    loop_vert = np.array([lp.vertex_index for lp in mesh.loops])
    on = np.isin(loop_vert, list(boundary))
    centre = uv[on].mean(axis=0)
    r = np.linalg.norm(uv[on] - centre, axis=1)
    assert r.std() <= 1e-4 * r.mean()
