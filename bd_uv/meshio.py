"""Reading and writing mesh files.

OBJ is read by ``obj.read_obj`` (by position index: the file's vertex order). OFF, PLY and STL
go through trimesh with ``process=False`` (vertex order kept), a binary PLY it misreads through
``ply.read_binary_ply``.

Exporters split a vertex wherever its normal or UV differs (OFF and PLY have no ``vt`` to do it
with); a file written face by face (every STL, three.js's exporters for unindexed geometry, many
PLY and OBJ converters) splits every vertex, so the unwrap would see one island a face. Vertices
at equal positions are therefore welded for the unwrap (``mesh.weld.welded_in_place``: never
where faces only touch at a point nor across an OBJ's objects; each named by the least of the
file's vertices, the vertex list unchanged), the file's UVs still mark its seams, and the file's
faces are written as they were. An OBJ is written back as its own text with only its UVs
replaced (``write_unwrapped``, ``obj.patched_obj``), its polygons kept.
"""
import os
from functools import cached_property
from dataclasses import dataclass

import numpy as np

from .errors import InvalidMeshError, refuse_lfs_pointer
from .mesh.weld import welded_in_place
from .obj import patched_obj, polygon_corner_vt, read_obj
from .ply import polygon_triangles, raw_polygons, read_binary_ply


@dataclass(frozen=True)
class Mesh:
    """A loaded triangle mesh.

    Attributes
    ----------
    V : (n,3) float64
    F : (m,3) int64 (polygons fan-triangulated)
    corner_uv : (m,3,2) float64 or None, the file's UVs per face corner (OBJ ``vt``)
    name : str
    labels : dict or None, what each face belongs to, for packing by group
        (``bd_uv.packing.pack_islands``' ``face_labels``): "material" (m,) int64 (OBJ
        ``usemtl``, glTF primitive materials, USD "materialBind" GeomSubsets; -1: none) and
        "object" (m,) int64 (OBJ ``o``); None when the format says nothing of it (OFF, PLY)
    file_F : (m,3) int64 or None, the faces as the file names their vertices, when ``F`` welds
        vertices the file split (OFF, PLY); what is written back
    polygons : (m,) int64 or None, an OBJ's polygon (``f`` record) of each face, its fan's
        triangles consecutive (``obj.read_obj``); None for other formats
    polygon_corners : (m,3) int64 or None, with ``polygons``: each face corner's place in its
        polygon (the fan from its first corner, or another where that has a face of no area)
    """
    V: np.ndarray
    F: np.ndarray
    corner_uv: np.ndarray = None
    name: str = ""
    labels: dict = None
    file_F: np.ndarray = None
    polygons: np.ndarray = None
    polygon_corners: np.ndarray = None

    @property
    def faces_to_write(self):
        """The faces as the file had them (its own vertex ids), for the OBJ written."""
        return self.F if self.file_F is None else self.file_F

    @property
    def face_groups(self):
        """The polygon of each face, for ``bd_uv.unwrap``'s ``face_groups`` (no seam or cut
        through a polygon, so each corner keeps one UV): None when every polygon is a triangle
        (or the format has none)."""
        p = self.polygons
        return None if p is None or len(p) == 0 or p[-1] + 1 == len(p) else p

    @cached_property
    def welded(self):
        """How many of the file's vertices were welded onto another at the same position."""
        if self.file_F is None:
            return 0
        return int(len(np.unique(self.file_F)) - len(np.unique(self.F)))

    def uv_seams(self):
        """Edges where the file's UVs are discontinuous, (s,2) vertex pairs; None without UVs."""
        if self.corner_uv is None:
            return None
        return uv_seams(self.F, self.corner_uv)


def load_mesh(path):
    """Load an OBJ, OFF, PLY or STL file.

    Returns
    -------
    Mesh

    Raises
    ------
    InvalidMeshError when the file cannot be read or holds no faces.
    """
    ext = os.path.splitext(path)[1].lower()
    name = os.path.splitext(os.path.basename(path))[0]
    refuse_lfs_pointer(path)
    try:
        labels, file_F, polygons, corners = None, None, None, None
        if ext == ".obj":
            V, F, cuv, labels, polygons, corners = read_obj(path)
            file_F, F = _welded(V, F, labels["object"])
        elif ext in (".off", ".ply", ".stl"):
            V, F, vuv = _read_trimesh(path, ext)
            cuv = None if vuv is None else vuv[F]
            file_F, F = _welded(V, F)
        else:
            raise InvalidMeshError(f"{path}: unsupported format {ext!r}; use .obj, .off, .ply "
                                   f"or .stl")
    except InvalidMeshError:
        raise
    except Exception as exc:   # trimesh's loaders fail in many ways on files they cannot parse
        raise InvalidMeshError(f"{path}: cannot read the mesh as {ext.lstrip('.').upper()} "
                               f"({type(exc).__name__}: {exc})") from exc
    if len(F) == 0:
        raise InvalidMeshError(f"{path}: the file holds no faces")
    return Mesh(V, F.reshape(-1, 3), cuv, name, labels, file_F, polygons, corners)


def welded_entry(mesh):
    """The report's word on a weld: ``{"welded_vertices": k}`` (the file's vertices welded onto
    another at the same position; its faces are written as they were), or nothing."""
    return {"welded_vertices": mesh.welded} if mesh.welded else {}


def _welded(V, F, parts=None):
    """(file_F, F): ``F`` with the vertices the file split at equal positions welded (within
    each of ``parts``, an OBJ's objects), and the file's own faces; (None, F) when nothing is
    welded."""
    F = F.reshape(-1, 3)
    if len(F) == 0 or not np.all((F >= 0) & (F < len(V))):
        return None, F       # the arrays' own check names what is wrong
    G = welded_in_place(V, F, parts)
    return (None, F) if np.array_equal(G, F) else (F, G)


def _read_trimesh(path, ext):
    """V, F and the vertices' UVs (a PLY's ``s t``/``u v``; None without) of an OFF, PLY or STL
    file through trimesh. An ASCII PLY whose body has blank lines or
    ``comment`` lines (hand-written files, some exporters) is read with those lines dropped:
    trimesh's ASCII reader takes the body as one run of numbers and misreads it otherwise."""
    import io

    import trimesh
    file_obj, file_type = path, None
    if ext == ".ply":
        with open(path, "rb") as fh:
            data = fh.read()
        head, sep, body = data.partition(b"end_header")
        if sep and b"\n" not in head and body[:1] == b"\r":
            # a header whose lines end in a lone CR (classic Mac; draco's Rhino Box.ply): LF,
            # byte for byte, so the body (binary or not) stays where the header says
            head, body = head.replace(b"\r", b"\n"), b"\n" + body[1:]
            data = head + sep + body
            file_obj, file_type = io.BytesIO(data), "ply"
        if sep and b"format ascii" in head:
            eol = body.find(b"\n")
            lines = body[eol + 1:].splitlines() if eol >= 0 else []
            keep = [ln for ln in lines if ln.strip() and not ln.lstrip().startswith(b"comment")]
            if len(keep) != len(lines):
                file_obj = io.BytesIO(head + sep + body[:eol + 1] + b"\n".join(keep) + b"\n")
                file_type = "ply"
    # skip_materials: a PLY's texture image (``comment TextureFile``) is not read: an unwrap
    # has no use for it, and one missing (a PLY copied alone: trimesh's fuze.ply) had trimesh
    # log a whole traceback to stderr on a run that succeeds. The file's UVs are read all the same.
    try:
        m = trimesh.load(file_obj, file_type=file_type, process=False, force="mesh",
                         skip_materials=True)
    except Exception as exc:
        if ext != ".ply" or b"format binary" not in head:
            raise
        try:   # faces of different lengths (triangles and quads: Rhino), which trimesh misreads
            return read_binary_ply(data)
        except ValueError:
            raise exc from None
    if ext == ".ply" and not len(m.faces) and b"format binary" in head \
            and b"element tristrips" in head:
        return read_binary_ply(data)   # triangle strips (Cyberware's igea.ply): no faces to trimesh
    V = np.asarray(m.vertices, dtype=np.float64)
    uv = getattr(m.visual, "uv", None)
    uv = None if uv is None or len(uv) != len(V) else np.asarray(uv, dtype=np.float64)[:, :2]
    F = np.asarray(m.faces, dtype=np.int64)
    try:
        corners = raw_polygons(m) if ext == ".ply" else None
    except ValueError:        # mixed face lengths trimesh read as one: walked here instead
        return read_binary_ply(data)
    if corners is not None:   # polygons: trimesh's fans replaced by polygons.triangulate's
        F = polygon_triangles(V, corners)
    return V, F, uv


def uv_seams(F, corner_uv):
    """Edges whose two faces disagree on the UV of either end, as (s,2) vertex pairs."""
    F = np.asarray(F, dtype=np.int64)
    n = int(F.max()) + 1
    a = F.ravel()
    b = np.roll(F, -1, axis=1).ravel()
    ua = corner_uv.reshape(-1, 2)
    ub = np.roll(corner_uv, -1, axis=1).reshape(-1, 2)
    key = np.minimum(a, b) * n + np.maximum(a, b)
    order = np.argsort(key, kind="stable")
    k = key[order]
    pair = np.flatnonzero(k[1:] == k[:-1])
    h1, h2 = order[pair], order[pair + 1]
    # Align: the end of h2 at vertex a[h1].
    same = a[h1] == a[h2]
    u2a = np.where(same[:, None], ua[h2], ub[h2])
    u2b = np.where(same[:, None], ub[h2], ua[h2])
    cut = np.any(ua[h1] != u2a, axis=1) | np.any(ub[h1] != u2b, axis=1)
    return np.stack([a[h1[cut]], b[h1[cut]]], axis=1)


#: why a polygon of an OBJ is written as its triangles, for the command line and the batch
AS_TRIANGLES = ("the UVs of their triangles differ at a corner (a cut ran through the polygon, "
                "or only some of its triangles were certified), which one UV per polygon corner "
                "cannot hold; each triangle keeps the UVs certified")


def polygons_as_triangles(mesh, F_uv):
    """How many of an OBJ's polygons (more than three corners) the file written from ``F_uv``
    (the ``vt`` of each face corner, -1 on faces not written) holds as their triangles: their
    triangles' UVs differ at a corner (a cut through the polygon), or only some are written. 0
    for other formats."""
    if mesh.face_groups is None:
        return 0
    return int((~polygon_corner_vt(mesh.polygons, F_uv, mesh.polygon_corners)[2]).sum())


def write_unwrapped(path, source, mesh, uv, F_uv):
    """Write the unwrapped ``mesh`` read from ``source`` as an OBJ at ``path``: an OBJ input's
    own text with its UVs replaced (``obj.patched_obj``: every other record kept, polygons
    kept where each corner has one UV), any other format's vertices and triangles
    (``write_obj``). ``uv``, ``F_uv``: ``Layout.vertex_uv``'s. Returns the polygons written as
    their triangles."""
    if mesh.polygons is None:
        write_obj(path, mesh.V, mesh.faces_to_write, uv, F_uv)
        return 0
    return patched_obj(source, path, mesh.faces_to_write, mesh.polygons, F_uv, uv,
                       mesh.polygon_corners)


def write_obj(path, V, F, uv=None, F_uv=None):
    """Write an OBJ with the input's vertices and faces in order, and ``f v/vt`` faces.

    Parameters
    ----------
    V : (n,3) float array
    F : (m,3) int array
    uv : (k,2) float array, optional, one ``vt`` per island vertex
    F_uv : (m,3) int array, optional, the ``vt`` of each face corner; -1 on faces without UVs
    """
    V = np.asarray(V, dtype=np.float64)
    F = np.asarray(F, dtype=np.int64)
    d = os.path.dirname(os.path.abspath(path))
    os.makedirs(d, exist_ok=True)
    with open(path, "w", encoding="utf-8") as fh:
        fh.write("# written by bd-uv\n")
        np.savetxt(fh, V, fmt="v %.17g %.17g %.17g")
        if uv is not None and len(uv):
            np.savetxt(fh, np.asarray(uv, dtype=np.float64), fmt="vt %.17g %.17g")
        if F_uv is None:
            np.savetxt(fh, F + 1, fmt="f %d %d %d")
            return
        F_uv = np.asarray(F_uv, dtype=np.int64)
        has = np.all(F_uv >= 0, axis=1)
        lines = np.empty(len(F), dtype=object)
        fv, ft = F + 1, F_uv + 1
        lines[has] = [f"f {a}/{p} {b}/{q} {c}/{r}" for (a, b, c), (p, q, r)
                      in zip(fv[has].tolist(), ft[has].tolist())]
        lines[~has] = [f"f {a} {b} {c}" for a, b, c in fv[~has].tolist()]
        fh.write("\n".join(lines.tolist()))
        fh.write("\n")
