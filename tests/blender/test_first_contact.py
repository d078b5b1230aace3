"""Issue 20: ``uv.bd_unwrap`` with every option at its default, as a new user runs it.

Each of Blender's primitives, a closed genus-2 mesh made by others (CGAL's ``eight.off``,
``tests/data``) and meshes with a bow-tie vertex or an edge of three faces: FINISHED, and every
face certified from the UVs as stored (float32): no flipped face, max distortion within the
default C = 5, recomputed here from an SVD per triangle (``conftest.triangle_distortion``). A mesh
whose marked seams already make certifiable disks (``uv.seams_from_islands``) gets no new seam.
"""
import pathlib

import numpy as np
import pytest

from conftest import bpy, loop_uv_array, set_mode, triangle_distortion
from test_bad_input_blender import _get, last, run
from test_operator_unwrap import SLACK, _loop_triangles

C = 5.0  # the operator's default bound
DATA = pathlib.Path(__file__).resolve().parents[1] / "data"

PRIMITIVES = {
    "uv_sphere": lambda: bpy.ops.mesh.primitive_uv_sphere_add(),
    "cube": lambda: bpy.ops.mesh.primitive_cube_add(),
    "torus": lambda: bpy.ops.mesh.primitive_torus_add(),
    "cylinder": lambda: bpy.ops.mesh.primitive_cylinder_add(),
    "cone": lambda: bpy.ops.mesh.primitive_cone_add(),
    "ico_sphere": lambda: bpy.ops.mesh.primitive_ico_sphere_add(),
    "grid": lambda: bpy.ops.mesh.primitive_grid_add(),
    "suzanne": lambda: bpy.ops.mesh.primitive_monkey_add(),
}


def _seams(mesh):
    return _get(mesh.edges, "use_seam", bool, len(mesh.edges))


def _unwrap_defaults(capsys, obj):
    """Select every face in Edit Mode and run the operator with no options; Object Mode after.

    Returns (result, reports)."""
    set_mode(obj, 'EDIT')
    bpy.ops.mesh.select_all(action='SELECT')
    result, reports = run(capsys)
    set_mode(obj, 'OBJECT')
    return result, reports


def _certified_as_stored(obj, bound=C):
    """Every triangle's stored UVs: none flipped, distortion <= bound (float32 slack). Returns
    the max distortion."""
    V, tris, loops, _ = _loop_triangles(obj)
    uv = loop_uv_array(obj.data)[loops]                      # (m,3,2) float32 as stored
    D, det = triangle_distortion(V, tris, uv)
    assert (det > 0).all(), f"{int((det <= 0).sum())} flipped triangles"
    assert D.max() <= bound * SLACK, D.max()
    return float(D.max())


def _from_arrays(name, V, F):
    mesh = bpy.data.meshes.new(name)
    mesh.from_pydata([tuple(v) for v in V], [], [tuple(int(i) for i in f) for f in F])
    mesh.update()
    obj = bpy.data.objects.new(name, mesh)
    bpy.context.scene.collection.objects.link(obj)
    return obj


@pytest.mark.parametrize("name", list(PRIMITIVES))
def test_every_primitive_unwraps_with_the_defaults(addon, capsys, name):
    PRIMITIVES[name]()
    obj = bpy.context.active_object
    seams_before = _seams(obj.data)
    result, reports = _unwrap_defaults(capsys, obj)
    assert result == {'FINISHED'}, reports
    assert last().islands >= 1
    _certified_as_stored(obj)
    # Marked seams are kept; the report says how many were added (and they are marked).
    seams_after = _seams(obj.data)
    assert not (seams_before & ~seams_after).any()
    added = int((seams_after & ~seams_before).sum())
    if added:
        assert f"{added} seam{'s' if added != 1 else ''} added" in reports[-1][1]
    else:
        assert "seams added" not in reports[-1][1]


def test_closed_genus_two_mesh_not_made_by_us(addon, capsys):
    from conftest import load_addon
    core = load_addon().bd_uv
    mesh = core.load_mesh(str(DATA / "eight.off"))
    obj = _from_arrays("eight", mesh.V, mesh.F)
    result, reports = _unwrap_defaults(capsys, obj)
    assert result == {'FINISHED'}, reports
    _certified_as_stored(obj)
    # A closed genus-2 surface cannot be unwrapped without seams: some were added and marked.
    assert _seams(obj.data).sum() > 0


@pytest.mark.parametrize("name", ["cube", "uv_sphere", "torus", "suzanne"])
def test_marked_seams_that_make_disks_get_no_new_seam(addon, capsys, name):
    # The primitive's own UV map's islands marked as seams (uv.seams_from_islands): every island
    # is a disk whose map is certifiable at C as it is, so nothing is added.
    PRIMITIVES[name]()
    obj = bpy.context.active_object
    set_mode(obj, 'EDIT')
    bpy.ops.mesh.select_all(action='SELECT')
    bpy.ops.uv.seams_from_islands()
    set_mode(obj, 'OBJECT')
    before = _seams(obj.data)
    assert before.sum() > 0
    result, reports = _unwrap_defaults(capsys, obj)
    assert result == {'FINISHED'}, reports
    np.testing.assert_array_equal(_seams(obj.data), before)
    assert "seam" not in reports[-1][1]
    _certified_as_stored(obj)


def _grid(nx, ny):
    xs, ys = np.meshgrid(np.arange(nx + 1, dtype=float), np.arange(ny + 1, dtype=float),
                         indexing="ij")
    V = np.stack([xs.ravel(), ys.ravel(), 0.1 * np.sin(xs.ravel() + ys.ravel())], axis=1)
    i = np.arange(nx)[:, None] * (ny + 1) + np.arange(ny)[None, :]
    quads = np.stack([i, i + ny + 1, i + ny + 2, i + 1], axis=-1).reshape(-1, 4)
    return V, quads


@pytest.mark.parametrize("seams", [None, 'AUTO'])
def test_bowtie_vertex_is_split_and_every_face_certified(addon, capsys, seams):
    # A 4 x 3 grid whose corner vertices (0,0) and (4,0) are one vertex: two fans meet there
    # while the faces stay one connected piece (a bow-tie inside one island). With the default
    # seams (Add Where Needed) and with Add Automatically (79b5f85 refused it whole there:
    # "split the vertex (Mesh > Split)").
    V, Q = _grid(4, 3)
    far = 4 * 4
    Q[Q == far] = 0
    obj = _from_arrays("bowtie", V, Q)
    if seams is None:
        result, reports = _unwrap_defaults(capsys, obj)
    else:
        set_mode(obj, 'EDIT')
        bpy.ops.mesh.select_all(action='SELECT')
        result, reports = run(capsys, seams=seams)
        set_mode(obj, 'OBJECT')
    assert result == {'FINISHED'}, reports
    assert "non-manifold vertex" in reports[-1][1]
    _certified_as_stored(obj)


def test_edge_of_three_faces_is_cut_and_every_face_certified(addon, capsys):
    V, Q = _grid(3, 3)
    a, b = 5, 9                                # an inner edge of the grid: (1,1)-(2,1)
    assert any(set((a, b)) <= set(q) for q in Q.tolist())
    V = np.vstack([V, [[1.5, 1.0, 1.0]]])
    faces = [tuple(q) for q in Q.tolist()] + [(a, b, len(V) - 1)]
    mesh = bpy.data.meshes.new("fin")
    mesh.from_pydata([tuple(v) for v in V], [], faces)
    mesh.update()
    obj = bpy.data.objects.new("fin", mesh)
    bpy.context.scene.collection.objects.link(obj)
    result, reports = _unwrap_defaults(capsys, obj)
    assert result == {'FINISHED'}, reports
    assert "three or more faces" in reports[-1][1]
    _certified_as_stored(obj)
    # The edge of three faces is marked as a seam (where the artist sees the cut).
    ends = np.sort(_get(obj.data.edges, "vertices", np.int32, len(obj.data.edges),
                        2).reshape(-1, 2), axis=1)
    edge = np.flatnonzero((ends[:, 0] == a) & (ends[:, 1] == b))
    assert _seams(obj.data)[edge].all()


def _revolution_patch(nu, nv, radius, height, offset):
    """A quad patch (nu x nv quads) around the z axis, not closed in u (an open patch, as the
    Utah teapot's), vertex (i, j) at offset + i * (nv + 1) + j."""
    u, v = np.meshgrid(np.linspace(0, 0.999, nu + 1), np.linspace(0, 1, nv + 1), indexing="ij")
    a, r = 2 * np.pi * u.ravel(), radius(v.ravel())
    P = np.stack([r * np.cos(a), r * np.sin(a), height(v.ravel(), a)], 1)
    i = (np.arange(nu)[:, None] * (nv + 1) + np.arange(nv)[None, :]).ravel()
    return P, np.stack([i, i + nv + 1, i + nv + 2, i + 1], 1) + offset


def test_island_put_back_never_lies_over_the_written_atlas(addon, capsys):
    # Three open quad patches like the teapot's: a body, a lid whose first ring has a radius of
    # 1e-7 (faces far below what float32 UVs resolve at the packed scale: the lid cannot be
    # stored certified) and a handle-like strip. On a mesh with no UV map, the lid's UVs "as they
    # were" are the new map's default squares, all over the atlas: they go back moved right by
    # whole tiles, and the report says so.
    body, qb = _revolution_patch(24, 16, lambda v: 1.5 + 0.5 * np.sin(np.pi * v),
                                 lambda v, a: 2 * v, 0)
    lid, ql = _revolution_patch(16, 12, lambda v: 1e-7 + (0.8 - 1e-7) * v ** 2,
                                lambda v, a: 2.5 - 0.5 * v + 0.05 * np.sin(8 * a) * v, len(body))
    V = np.vstack([body, lid])
    obj = _from_arrays("pot", V, np.vstack([qb, ql]))
    result, reports = _unwrap_defaults(capsys, obj)
    assert result == {'FINISHED'}, reports
    level, message = reports[-1]
    Vt, tris, loops, poly = _loop_triangles(obj)
    uv = loop_uv_array(obj.data)[loops].astype(np.float64)
    lid_tris = poly >= len(qb)
    D, det = triangle_distortion(Vt, tris, uv)
    if "put back" not in message:       # a future fix may store the lid certified: all good then
        _certified_as_stored(obj)
        return
    assert level == 'WARNING' and "moved 1 UV tile right" in message, message
    back = uv[:, :, 0].min(axis=1) >= 1.0
    assert np.array_equal(back, lid_tris)                    # exactly the lid went back
    assert uv[~back][:, :, 0].max() <= 1.0                   # the atlas stays in its tile
    assert (det[~back] > 0).all() and D[~back].max() <= C * SLACK


def test_duplicate_polygon_gets_its_twins_uvs(addon, capsys):
    # Two quads of a strip, the first one given twice (same vertices, same order).
    V = np.array([(0, 0, 0), (1, 0, 0), (2, 0, 0), (0, 1, 0), (1, 1, 0.2), (2, 1, 0)], float)
    obj = _from_arrays("dup", V, np.array([(0, 1, 4, 3), (1, 2, 5, 4), (0, 1, 4, 3)]))
    result, reports = _unwrap_defaults(capsys, obj)
    assert result == {'FINISHED'}, reports
    assert "1 duplicate face(s)" in reports[-1][1], reports
    _certified_as_stored(obj)
    mesh = obj.data
    uv = loop_uv_array(mesh)
    loop_vert = _get(mesh.loops, "vertex_index", np.int32, len(mesh.loops))
    first, third = mesh.polygons[0], mesh.polygons[2]
    def by_vertex(p):
        return {int(loop_vert[i]): tuple(uv[i]) for i in range(p.loop_start,
                                                                p.loop_start + p.loop_total)}
    assert by_vertex(first) == by_vertex(third)


def test_zero_area_face_is_named_and_kept_off_the_atlas(addon, capsys):
    # Two quads and a triangle on three collinear points (zero area), no UV map yet.
    V = np.array([(0, 0, 0), (1, 0, 0), (2, 0, 0), (0, 1, 0), (1, 1, 0.2), (2, 1, 0),
                  (0.5, 0, 0)], float)
    mesh = bpy.data.meshes.new("zero")
    mesh.from_pydata([tuple(v) for v in V], [], [(0, 1, 4, 3), (1, 2, 5, 4), (0, 6, 1)])
    mesh.update()
    obj = bpy.data.objects.new("zero", mesh)
    bpy.context.scene.collection.objects.link(obj)
    result, reports = _unwrap_defaults(capsys, obj)
    assert result == {'FINISHED'}, reports
    level, message = reports[-1]
    assert level == 'WARNING' and "zero-area" in message and "faces 2" in message, message
    uv = loop_uv_array(obj.data)
    tri = obj.data.polygons[2]
    quads = np.arange(tri.loop_start)
    # The zero-area face holds the new map's default UVs, moved right by whole tiles: off the
    # quads, which are certified as stored.
    assert uv[tri.loop_start:tri.loop_start + 3, 0].min() >= uv[quads, 0].max()
    Vt, tris, loops, poly = _loop_triangles(obj)
    D, det = triangle_distortion(Vt, tris[poly < 2], uv[loops[poly < 2]])
    assert (det > 0).all() and D.max() <= C * SLACK


def test_batch_script_unwraps_closed_primitives_with_its_defaults(empty_scene, tmp_path):
    """scripts/bd_uv_batch.py with no options on a .blend of closed primitives (no seams, no UV
    map): every object certified, the seams it added marked in the saved file, the saved UVs
    certified (recomputed here)."""
    import json
    from test_post_write_check import _load_script

    bpy.ops.mesh.primitive_uv_sphere_add(segments=16, ring_count=8)
    bpy.ops.mesh.primitive_torus_add(location=(4, 0, 0))
    for ob in bpy.context.scene.objects:
        while ob.data.uv_layers:
            ob.data.uv_layers.remove(ob.data.uv_layers[0])
    blend, out, report = tmp_path / "in.blend", tmp_path / "out.blend", tmp_path / "r.json"
    bpy.ops.wm.save_as_mainfile(filepath=str(blend))
    script = _load_script()
    assert script.main([str(script.__file__), str(blend), "--", "--output", str(out),
                        "--report", str(report)]) == 0
    items = json.loads(report.read_text())["items"]
    assert {e["object"] for e in items} == {"Sphere", "Torus"}
    bpy.ops.wm.open_mainfile(filepath=str(out))
    for e in items:
        assert e["status"] == "certified" and len(e["seams_added"]) > 0, e
        obj = bpy.data.objects[e["object"]]
        assert _seams(obj.data).sum() == e["seams_marked"] > 0
        _certified_as_stored(obj)


def _split_grid():
    """A curved quad grid at scale 100 split by a strip of 4 quads one float32 step high, as a
    Blender object: (object, number of grid quads, the strip's edges as vertex pairs)."""
    nx, ny = 5, 4
    xs, ys = np.meshgrid(np.linspace(0.0, 1.0, nx), np.linspace(0.0, 1.0, ny))
    x, y = xs.ravel(), ys.ravel()
    V = 100.0 * np.stack([x, y, 0.25 * (x - 0.4) ** 2 + 0.1 * y], axis=1)
    i = np.arange(nx * ny).reshape(ny, nx)
    quads = [list(q) for q in np.stack([i[:-1, :-1].ravel(), i[:-1, 1:].ravel(),
                                        i[1:, 1:].ravel(), i[1:, :-1].ravel()], axis=1)]
    row = i[1]
    copy = {int(r): len(V) + k for k, r in enumerate(row)}
    eps = float(np.spacing(np.float32(V[row[0], 1])))
    V = np.vstack([V, V[row] + [0.0, eps, 0.0]]).astype(np.float32).astype(np.float64)
    for q in quads[nx - 1:]:                     # the rows above the split take the copies
        q[:] = [copy.get(int(v), int(v)) for v in q]
    strip = [[int(row[k]), int(row[k + 1]), copy[int(row[k + 1])], copy[int(row[k])]]
             for k in range(nx - 1)]
    mesh = bpy.data.meshes.new("split")
    mesh.from_pydata([tuple(v) for v in V], [], quads + strip)
    mesh.update()
    obj = bpy.data.objects.new("split", mesh)
    bpy.context.scene.collection.objects.link(obj)
    sides = {frozenset(q[:2]) for q in strip} | {frozenset(q[2:]) for q in strip}
    return obj, len(quads), sides


def _rest_certified(obj, n_quads):
    """The split grid's 8 strip triangles left out; every other face certified as stored."""
    Vt, tris, loops, poly = _loop_triangles(obj)
    keep = poly < n_quads
    assert (~keep).sum() == 8
    uv = loop_uv_array(obj.data)
    D, det = triangle_distortion(Vt, tris[keep], uv[loops[keep]])
    assert (det > 0).all() and D.max() <= C * SLACK


def test_faces_float32_cannot_tell_from_a_line_side_by_side_are_left_out(addon, capsys):
    """A curved quad grid at scale 100 split by a strip of 4 quads one float32 step high
    (OpenChessSet's bishops hold 608 such faces in strips). Blender stores positions in float32;
    no UV store keeps the strip's 8 triangles apart, at any stretch, and trying failed the whole
    grid. They are left out as zero-area from the start (named), every other face certified as
    stored (recomputed here)."""
    obj, n_quads, _ = _split_grid()
    result, reports = _unwrap_defaults(capsys, obj)
    assert result == {'FINISHED'}, reports
    assert any("zero-area" in m for _, m in reports), reports
    _rest_certified(obj, n_quads)


def test_marked_seams_refuse_float32_flat_faces_at_once(addon, capsys):
    """Seams "Marked" on the same grid with the strip's two long sides marked: the strip's
    island, which no float32 store keeps apart, is refused at once as zero-area (named), not
    after solves that cannot certify it; the two halves are certified as stored (recomputed)."""
    obj, n_quads, sides = _split_grid()
    for e in obj.data.edges:
        e.use_seam = frozenset(e.vertices) in sides
    set_mode(obj, 'EDIT')
    bpy.ops.mesh.select_all(action='SELECT')
    result, reports = run(capsys, seams='MARKED')
    set_mode(obj, 'OBJECT')
    assert result == {'FINISHED'}, reports
    assert any("zero-area" in m for _, m in reports), reports
    Vt, tris, loops, poly = _loop_triangles(obj)
    keep = poly < n_quads
    uv = loop_uv_array(obj.data)
    D, det = triangle_distortion(Vt, tris[keep], uv[loops[keep]])
    assert (det > 0).all() and D.max() <= C * SLACK


@pytest.mark.parametrize("bowtie", [False, True])
def test_add_automatically_leaves_float32_flat_faces_out(addon, capsys, bowtie):
    """Seams "Add Automatically" on the split grid, as it is and with a bow-tie (its corners
    (0,0) and (4,0) one vertex): the repair runs before the search and takes Blender's float32
    storage as "Add Where Needed" does: the strip's 8 triangles, which no float32 store keeps
    apart, are left out as zero-area (named), every other face certified as stored
    (recomputed). On 0926a43 the grid as it is was CANCELLED (its chart, strip and all, failed
    as stored), and with the bow-tie the strip was kept in a chart, unnamed, its stored UVs at
    distortion 6.7e6 measured from the float32 positions."""
    obj, n_quads, _ = _split_grid()
    if bowtie:
        V = np.array([v.co[:] for v in obj.data.vertices], dtype=np.float64)
        faces = [[0 if v == 4 else v for v in p.vertices] for p in obj.data.polygons]
        bpy.data.objects.remove(obj)
        obj = _from_arrays("split_bowtie", V, faces)
    set_mode(obj, 'EDIT')
    bpy.ops.mesh.select_all(action='SELECT')
    result, reports = run(capsys, seams='AUTO')
    set_mode(obj, 'OBJECT')
    assert result == {'FINISHED'}, reports
    assert ("non-manifold vertex" in reports[-1][1]) == bowtie, reports
    assert any("zero-area" in m for _, m in reports), reports
    _rest_certified(obj, n_quads)


@pytest.mark.parametrize("name", ["uv_sphere", "cube", "torus", "suzanne"])
def test_minimise_with_the_default_seams_certifies_every_face_lower(addon, capsys, name):
    """Minimise with the default seams (Add Where Needed): it took the islands as they were,
    and Blender's closed primitives were CANCELLED ("add seams"); now seams are added where
    needed and every island and chart gets its least C: FINISHED, every face certified as
    stored (recomputed), and no face above the default unwrap's worst."""
    worst = {}
    for minimise in (False, True):
        for ob in list(bpy.data.objects):
            bpy.data.objects.remove(ob)
        PRIMITIVES[name]()
        obj = bpy.context.active_object
        set_mode(obj, 'EDIT')
        bpy.ops.mesh.select_all(action='SELECT')
        result, reports = run(capsys, minimise=minimise)
        set_mode(obj, 'OBJECT')
        assert result == {'FINISHED'}, reports
        worst[minimise] = _certified_as_stored(obj)
    assert worst[True] <= worst[False] * SLACK, worst


def _packed_coverage(obj):
    """The stored UVs' triangle area inside the unit square (float32 as stored)."""
    V, tris, loops, _ = _loop_triangles(obj)
    uv = loop_uv_array(obj.data)[loops].astype(np.float64)
    assert ((uv >= 0) & (uv <= 1)).all()
    e1, e2 = uv[:, 1] - uv[:, 0], uv[:, 2] - uv[:, 0]
    return float(0.5 * np.abs(e1[:, 0] * e2[:, 1] - e1[:, 1] * e2[:, 0]).sum())


@pytest.mark.parametrize("seams", ['NEEDED', 'AUTO'])
def test_atlas_cuts_cut_the_torus_band_unless_turned_off(addon, capsys, seams):
    # Blender's default torus: the handle cuts open it into one band that caps the atlas at a
    # third; Atlas Cuts (the default) cut the band in two, marked and reported as the atlas's,
    # and the packed UVs cover far more. Off: the minimal seams, one band.
    found = {}
    for atlas in (True, False):
        for ob in list(bpy.data.objects):
            bpy.data.objects.remove(ob)
        PRIMITIVES["torus"]()
        obj = bpy.context.active_object
        set_mode(obj, 'EDIT')
        bpy.ops.mesh.select_all(action='SELECT')
        result, reports = run(capsys, seams=seams, atlas_cuts=atlas)
        set_mode(obj, 'OBJECT')
        assert result == {'FINISHED'}, reports
        _certified_as_stored(obj)
        found[atlas] = (last().islands, int(_seams(obj.data).sum()), _packed_coverage(obj),
                        reports[-1][1])
    (on_islands, on_seams, on_cov, on_msg), (off_islands, off_seams, off_cov, off_msg) = (
        found[True], found[False])
    assert (on_islands, off_islands) == (2, 1)
    assert on_seams > off_seams
    assert "1 atlas cut" in on_msg and "atlas" not in off_msg
    assert on_cov >= 1.5 * off_cov, (on_cov, off_cov)
