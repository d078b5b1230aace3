"""One USD mesh prim as arrays: points, triangles (polygons kept as face groups, fans where sound,
concave polygons ear-clipped, a fan turned where a diagonal would lie on another polygon's
side), holes left out, the UV primvar's values per triangle corner, each face's material; every
value read checked to be numbers of the right shape (a damaged file is a ``SceneFileError``
naming the prim, not a numpy error). Shared by the stage's
own meshes and the instanced ones (``usd``, ``usd_instances``).
"""
import numpy as np

from ..errors import SceneFileError
from ..meshio import Mesh
from ..polygons import triangulate
from .model import SceneMesh
from .usd_uv_name import uv_primvar


def polygon_triangles(V, counts, indices):
    """``polygons.triangulate`` (fans, concave polygons ear-clipped), with the fan of a
    polygon turned to start at another corner where one of its diagonals would run along an edge
    of the mesh (a non-planar pentagon whose fan diagonal lies on its neighbour's side, usd-wg's
    ``5_face.usda``): such a diagonal makes an edge of three triangles, which splits the polygon
    across islands.

    Returns
    -------
    T : (m,3) int64 face-vertex ids, poly : (m,) int64 polygon of each triangle
    """
    # float32: the precision a scene's faces are measured at (``batch.scene_files``), so no
    # fan triangle is kept that it cannot tell from a line
    T, poly, clipped = triangulate(V, counts, indices, precision=np.float32)
    counts = np.asarray(counts, dtype=np.int64)
    big = np.flatnonzero(counts >= 4)
    if not len(big) or not len(indices):
        return T, poly
    idx = np.asarray(indices, dtype=np.int64)
    n = int(idx.max()) + 1
    start = np.concatenate([[0], np.cumsum(counts)[:-1]])
    pos = np.arange(len(idx)) - np.repeat(start, counts)
    nxt = np.repeat(start, counts) + (pos + 1) % np.repeat(counts, counts)
    a, b = idx, idx[nxt]
    sides = np.unique(np.minimum(a, b) * n + np.maximum(a, b))
    # the fan's diagonals: its first two and last two triangles' shared edges (s, s+i+1)
    d = T[:, [0, 2]]
    inner = np.r_[poly[1:] == poly[:-1], False]          # a triangle followed by its polygon's
    key = np.minimum(idx[d[:, 0]], idx[d[:, 1]]) * n + np.maximum(idx[d[:, 0]], idx[d[:, 1]])
    bad = np.setdiff1d(poly[inner & np.isin(key, sides)], clipped)   # fans only
    if not len(bad):
        return T, poly
    for p in bad:   # rare: each such polygon's fan tried from its other corners
        c, s0 = int(counts[p]), int(start[p])
        ring = idx[s0:s0 + c]
        for k in range(1, c):
            diag = [(ring[k], ring[(k + j) % c]) for j in range(2, c - 1)]
            if not np.isin([min(u, v) * n + max(u, v) for u, v in diag], sides).any():
                rows = slice(*np.searchsorted(poly, [p, p + 1]))   # poly is sorted
                j = np.arange(1, c - 1)
                T[rows] = s0 + np.stack([np.full(c - 2, k), (k + j) % c, (k + j + 1) % c], 1)
                break
    return T, poly


def _nothing(attr, value):
    """True for an attribute not authored at all, or authored as an empty array (a damaged
    value, authored but unreadable, is not nothing)."""
    if attr.GetNumTimeSamples():
        return False
    if value is None:
        return not attr.HasAuthoredValue()
    return hasattr(value, "__len__") and len(value) == 0


def _sole_sample(attr, warnings):
    """The attribute's default value; with none, its one time sample (Houdini's exports and
    OpenUSD's animatedTop tutorial author the whole topology at one time code, no default)."""
    value = attr.Get()
    if value is None and attr.GetNumTimeSamples() == 1:
        t = attr.GetTimeSamples()[0]
        value = attr.Get(t)
        warnings.append(f"{attr.GetName()} is time-sampled with no default: read at time {t:g}")
    return value


def mesh_arrays(mesh, where, uv_name, Usd):
    """(Mesh, write-back part, info, warnings) of one UsdGeom.Mesh; None for an empty one
    (points, faceVertexCounts and faceVertexIndices all unauthored or empty)."""
    from pxr import UsdGeom
    warnings = []
    points_attr = mesh.GetPointsAttr()
    P = points_attr.Get(Usd.TimeCode.Default())
    if P is None and points_attr.GetNumTimeSamples():
        t = points_attr.GetTimeSamples()[0]
        P = points_attr.Get(t)
        warnings.append(f"points are time-sampled with no default: unwrapped at time {t:g}")
    counts = _sole_sample(mesh.GetFaceVertexCountsAttr(), warnings)
    indices = _sole_sample(mesh.GetFaceVertexIndicesAttr(), warnings)
    if (_nothing(points_attr, P) and _nothing(mesh.GetFaceVertexCountsAttr(), counts)
            and _nothing(mesh.GetFaceVertexIndicesAttr(), indices)):
        return None
    if not uv_name:   # the primvar the mesh's materials read its UVs from (usd_uv_name)
        uv_name, note = uv_primvar(mesh.GetPrim())
        if note:
            warnings.append(note)
    for attr in (mesh.GetFaceVertexCountsAttr(), mesh.GetFaceVertexIndicesAttr()):
        if attr.GetNumTimeSamples() > 1:   # before the default's absence is named below
            raise SceneFileError(f"{where}: {attr.GetName()} is time-sampled (changing "
                                 "topology); bd-uv unwraps one topology")
    if P is None or counts is None or indices is None:
        raise SceneFileError(f"{where}: a mesh without points, faceVertexCounts or "
                             "faceVertexIndices")
    V = _numbers(P, np.float64, f"{where}: points", width=3)
    counts = _numbers(counts, np.int64, f"{where}: faceVertexCounts")
    indices = _numbers(indices, np.int64, f"{where}: faceVertexIndices")
    if counts.sum() != len(indices):
        raise SceneFileError(f"{where}: faceVertexCounts sum to {int(counts.sum())} but there "
                             f"are {len(indices)} faceVertexIndices")
    if len(counts) and counts.min() < 3:
        bad = int(np.flatnonzero(counts < 3)[0])
        raise SceneFileError(f"{where}: face {bad} has {int(counts[bad])} vertices (< 3)")
    if len(indices) and (indices.min() < 0 or indices.max() >= len(V)):
        raise SceneFileError(f"{where}: a faceVertexIndex is out of range ({len(V)} points)")
    T, poly = polygon_triangles(V, counts, indices)
    holes = _numbers(mesh.GetHoleIndicesAttr().Get() or [], np.int64, f"{where}: holeIndices")
    keep = ~np.isin(poly, holes)
    T, poly = T[keep], poly[keep]
    if mesh.GetOrientationAttr().Get() == UsdGeom.Tokens.leftHanded:
        T = T[:, ::-1].copy()                    # the front face winds clockwise
    F = _one_vertex_a_place(V, counts, indices)[T]
    corner_uv = _existing_uv(mesh, uv_name, T, indices, len(V), where, warnings)
    info = {"prim": str(mesh.GetPath()), "uv_name": uv_name, "polygons": int(len(counts)),
            "holes": int(len(holes)),
            "subdivision": str(mesh.GetSubdivisionSchemeAttr().Get())}
    part = {"T": T, "poly": poly, "n_face_vertices": len(indices), "warnings": warnings,
            "uv_name": uv_name}
    # one prim is one object; each face's material from its "materialBind" GeomSubset
    labels = {"object": np.zeros(len(F), np.int64),
              "material": _subset_materials(mesh, len(counts))[poly]}
    return Mesh(V, F, corner_uv, str(mesh.GetPath()), labels), part, info, warnings


def _one_vertex_a_place(V, counts, indices):
    """The face-vertex indices the unwrap solves on: a polygon corner at exactly the place of
    the corner before it, though another point, takes that corner's point (as an OBJ's or a
    PLY's vertices at one place are welded). Every triangulation of such a polygon has a
    triangle of no area on the side between them, which the unwrap leaves out; unless the two
    corners are one vertex, the polygon's other triangles then meet only at a point, fall into
    two islands, and its face-vertices at that point get two UVs, which one UV per face-vertex
    cannot store (found by the polygon fuzz contract: such stars failed as stored, "max
    distortion 17.2 > bound 5"). A polygon of no area keeps its points (all its triangles are
    left out, their corners take the UVs of the same points in the faces beside them). The
    file's indices are not changed."""
    at = V[indices]
    counts = np.asarray(counts, dtype=np.int64)
    start = np.concatenate([[0], np.cumsum(counts)[:-1]])
    prev = np.arange(len(indices)) - 1
    prev[start] = start + counts - 1
    same = (at == at[prev]).all(axis=1) & (indices != indices[prev])
    if not same.any():
        return indices
    out = indices.copy()
    owner = np.repeat(np.arange(len(counts)), counts)
    for p in np.unique(owner[same]).tolist():
        s, c = int(start[p]), int(counts[p])
        moved = ~same[s:s + c]
        Q = at[s:s + c]
        twice = np.linalg.norm(np.cross(Q, np.roll(Q, -1, axis=0)).sum(axis=0))
        if not twice > 1e-12 * np.ptp(Q, axis=0).max() ** 2:
            continue                   # a polygon of no area: its corners keep their points
        first = int(np.argmax(moved))  # a corner away from the one before it
        for k in range(1, c):          # each corner of a run at one place: the run's first
            j = s + (first + k) % c
            if same[j]:
                out[j] = out[prev[j]]
    return out


def _subset_materials(mesh, n_faces):
    """(n_faces,) int64: each face's material, numbered by the material its "materialBind"
    GeomSubset binds (two subsets bound to one material are one; a subset without a binding is
    its own); faces in no such subset share the prim's own (number -1)."""
    from pxr import UsdGeom, UsdShade
    out = np.full(n_faces, -1, dtype=np.int64)
    names = {}
    for subset in UsdGeom.Subset.GetGeomSubsets(mesh, UsdGeom.Tokens.face, "materialBind"):
        material, _ = UsdShade.MaterialBindingAPI(subset.GetPrim()).ComputeBoundMaterial()
        key = str(material.GetPath()) if material else str(subset.GetPath())
        faces = _numbers(subset.GetIndicesAttr().Get() or [], np.int64,
                         f"{subset.GetPath()}: indices")
        faces = faces[(faces >= 0) & (faces < n_faces)]
        out[faces] = names.setdefault(key, len(names))
    return out


def _numbers(value, dtype, what, width=None):
    """An attribute's value as a numpy array of ``dtype`` ((n, width) when ``width`` is given), or
    SceneFileError naming it: a damaged file can hold a value of an unknown type (pxr's
    ``UnregisteredValue``) or of the wrong shape where numbers belong."""
    try:
        arr = np.asarray(value, dtype=dtype)
    except (TypeError, ValueError):
        raise SceneFileError(f"{what} is not an array of numbers (a {type(value).__name__}); "
                             "the file is damaged or not USD this reads") from None
    if width is not None and (arr.ndim != 2 or arr.shape[1] != width) and arr.size:
        raise SceneFileError(f"{what} is not {width} numbers per element (shape {arr.shape})")
    return arr.reshape(-1, width) if width is not None else arr.reshape(-1)


def _existing_uv(mesh, uv_name, T, indices, n_points, where="", warnings=None):
    """The mesh's UVs per triangle corner (m,3,2), or None. A primvar whose values or indices are
    only time-sampled (no default: Blender 4.1's animated UV indices) is read at its first time
    sample, as the points are (``warnings`` says so)."""
    from pxr import Usd, UsdGeom
    pv = UsdGeom.PrimvarsAPI(mesh.GetPrim()).GetPrimvar(uv_name)
    if not pv or not pv.HasValue():
        return None
    time = Usd.TimeCode.Default()
    sampled = [a for a in (pv.GetAttr(), pv.GetIndicesAttr())
               if a and a.GetNumTimeSamples() and a.Get(time) is None]
    if sampled:
        time = Usd.TimeCode(min(a.GetTimeSamples()[0] for a in sampled))
        if warnings is not None:
            warnings.append(f"primvars:{uv_name} is time-sampled with no default: its seams "
                            f"are read at time {time.GetValue():g}")
    vals = pv.ComputeFlattened(time)
    if vals is None:
        return None
    try:
        vals = np.asarray(vals, dtype=np.float64)
    except (TypeError, ValueError):
        raise SceneFileError(f"{where}: primvars:{uv_name} is not an array of numbers (a "
                             f"{type(vals).__name__}); the file is damaged") from None
    if vals.ndim != 2 or vals.shape[1] != 2:
        return None
    interp = pv.GetInterpolation()
    if interp == UsdGeom.Tokens.faceVarying and len(vals) == len(indices):
        return vals[T]
    if interp in (UsdGeom.Tokens.vertex, UsdGeom.Tokens.varying) and len(vals) == n_points:
        return vals[indices[T]]
    return None


def scene_mesh(mesh, where, name, uv_name, errors, Usd):
    """One UsdGeom.Mesh as the scene's (SceneMesh, write-back part), named ``name``: refused by
    name (part None) when its values are malformed, the stage's other meshes read on; None for
    an empty one (``mesh_arrays``). ``errors``: composition errors said on every mesh."""
    try:
        arrays = mesh_arrays(mesh, where, uv_name, Usd)
    except SceneFileError as exc:
        why = str(exc).removeprefix(f"{where}: ")   # the entry names the prim
        return SceneMesh(name, None, {"prim": name}, why, None, list(errors)), None
    if arrays is None:   # a placeholder a variant or payload fills: nothing to unwrap
        return None
    m, part, info, warnings = arrays
    return (SceneMesh(name, m, {**info, "prim": name}, None, part["poly"], warnings + errors),
            part)
