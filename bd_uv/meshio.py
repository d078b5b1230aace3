"""Reading and writing mesh files.

OBJ is read by position index (``v`` records) so vertex order is the file's own; loaders that
split vertices at UV seams would change the topology. OFF, PLY and STL go through trimesh with
``process=False`` (vertex order kept).

Exporters split a vertex wherever its normal or UV differs (OFF and PLY have no ``vt`` to do it
with); a file written face by face (every STL, three.js's exporters for unindexed geometry, many
PLY and OBJ converters) splits every vertex, so the unwrap would see one island a face. Vertices
at equal positions are therefore welded for the unwrap (``mesh.weld.welded_in_place``: never
where faces only touch at a point nor across an OBJ's objects; each named by the least of the
file's vertices, the vertex list unchanged), the file's UVs still mark its seams, and the file's
faces are written as they were.
"""
import os
import re
from dataclasses import dataclass

import numpy as np

from .errors import InvalidMeshError, refuse_lfs_pointer
from .mesh.weld import welded_in_place
from .ply import read_binary_ply

_COMMENT = re.compile(r"\s#.*")   # an OBJ comment after a record (a '#' inside a name stays)


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
    """
    V: np.ndarray
    F: np.ndarray
    corner_uv: np.ndarray = None
    name: str = ""
    labels: dict = None
    file_F: np.ndarray = None

    @property
    def faces_to_write(self):
        """The faces as the file had them (its own vertex ids), for the OBJ written."""
        return self.F if self.file_F is None else self.file_F

    @property
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
        labels, file_F = None, None
        if ext == ".obj":
            V, F, cuv, labels = _read_obj(path)
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
    return Mesh(V, F.reshape(-1, 3), cuv, name, labels, file_F)


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
    try:
        m = trimesh.load(file_obj, file_type=file_type, process=False, force="mesh")
    except Exception as exc:
        if ext != ".ply" or b"format binary" not in head:
            raise
        try:   # faces of different lengths (triangles and quads: Rhino), which trimesh misreads
            return read_binary_ply(data)
        except ValueError:
            raise exc from None
    V = np.asarray(m.vertices, dtype=np.float64)
    uv = getattr(m.visual, "uv", None)
    uv = None if uv is None or len(uv) != len(V) else np.asarray(uv, dtype=np.float64)[:, :2]
    return V, np.asarray(m.faces, dtype=np.int64), uv


def _read_obj(path):
    """V, F, corner UVs or None, and each face's material (``usemtl``) and object (``o``), each
    numbered in order of first use by a face (faces before any ``usemtl`` or ``o`` make a
    material or object of their own).

    A negative index counts back from the last ``v`` (``vt``) read before its face, as the OBJ
    format defines it (files written object by object use ``f -4 -3 -2 -1``). Records may be
    separated by tabs; a file starting with a UTF-16 byte order mark is read as UTF-16. An
    index naming no vertex is an ``InvalidMeshError`` giving the file's line."""
    vs, vts, faces, tfaces, mats, objs, numbers = [], [], [], [], [], [], []
    mat, obj = None, None
    for number, line in _obj_records(_obj_text(path)):
        line = _COMMENT.sub("", line)   # "f 1 2 3 # note": a comment ends a record
        tokens = line.split()
        key = tokens[0] if tokens else ""
        if key == "usemtl":
            mat = line.split(None, 1)[1].strip() if len(tokens) > 1 else ""
        elif key == "o":
            obj = line.split(None, 1)[1].strip() if len(tokens) > 1 else ""
        elif key == "v":
            vs.append((number, tokens[1:4]))
        elif key == "vt":
            vts.append((number, tokens[1:3]))
        elif key == "f" and len(tokens) > 3:
            items = [it.split("/") for it in tokens[1:]]
            vi = [_obj_index(path, number, it[0], len(vs), "v") for it in items]
            ti = [_obj_index(path, number, it[1], len(vts), "vt") + 1
                  if len(it) > 1 and it[1] else 0 for it in items]
            for j in range(1, len(vi) - 1):  # fan-triangulate polygons
                faces.append((vi[0], vi[j], vi[j + 1]))
                tfaces.append((ti[0], ti[j], ti[j + 1]))
                mats.append(mat)
                objs.append(obj)
                numbers.append(number)
    V = _numbers(path, vs, "v", 3)
    F = np.asarray(faces, dtype=np.int64).reshape(-1, 3)
    T = np.asarray(tfaces, dtype=np.int64).reshape(-1, 3)   # 1-based; 0: no vt
    _check_forward(path, F, len(V), "v", numbers)
    cuv = None
    if len(vts) and len(T) and np.all(T != 0):
        VT = _numbers(path, vts, "vt", 2)
        _check_forward(path, T - 1, len(VT), "vt", numbers)
        cuv = VT[T - 1]
    labels = {"material": _first_use(mats), "object": _first_use(objs)}
    return V, F, cuv, labels


def _numbers(path, rows, record, width):
    """(len(rows), width) float64 of the (line number, tokens) ``rows`` of ``record``s; a value
    that is not a number, or a record too short, is an ``InvalidMeshError`` giving its line."""
    try:
        return np.asarray([t for _, t in rows], dtype=np.float64).reshape(-1, width)
    except ValueError:
        pass
    for number, tokens in rows:
        if len(tokens) < width:
            raise InvalidMeshError(f"{path} line {number}: a {record} record needs {width} "
                                   f"numbers, this one has {len(tokens)}")
        for t in tokens:
            try:
                float(t)
            except ValueError:
                raise InvalidMeshError(f"{path} line {number}: {t!r} in a {record} record is "
                                       f"not a number") from None
    raise InvalidMeshError(f"{path}: the {record} records cannot be read as numbers")


def _obj_records(text):
    """(line number, record) of each record of an OBJ's text: a line ending in a backslash goes
    on on the next line (the OBJ format's continuation, as Rhino writes long faces); the number
    is the record's first line."""
    pending, start = None, 0
    for number, line in enumerate(text.splitlines(), 1):
        if pending is not None:
            line, number = pending + " " + line, start
        body = line.rstrip()
        if body.endswith("\\"):
            pending, start = body[:-1], number
            continue
        pending = None
        yield number, line
    if pending is not None:
        yield start, pending


def _obj_text(path):
    """The OBJ file's text: UTF-8 (bytes that are not are replaced), or UTF-16 after its BOM."""
    with open(path, "rb") as fh:
        raw = fh.read()
    if raw[:2] in (b"\xff\xfe", b"\xfe\xff"):
        return raw.decode("utf-16", errors="replace")
    return raw.decode("utf-8-sig", errors="replace")


def _obj_index(path, number, text, count, record):
    """The 0-based index of ``text`` (1-based, or negative from the last of the ``count``
    ``record``s read so far); a positive index past ``count`` is kept (a later record may
    define it: ``_check_forward``)."""
    try:
        i = int(text)
    except ValueError:
        raise InvalidMeshError(f"{path} line {number}: {text!r} is not a {record} index") from None
    if i < -count and not count:
        raise InvalidMeshError(f"{path} line {number}: face uses {record} {i}, but no {record} "
                               f"record comes before it (a negative index counts back from "
                               f"the {record} records before the face)")
    if i == 0 or i < -count:
        raise InvalidMeshError(
            f"{path} line {number}: face uses {record} {i}, but {count} {record} record(s) come "
            f"before it ({record} indices run 1..{count}, or -1..-{count} counting back)")
    return i + count if i < 0 else i - 1


def _check_forward(path, F, count, record, numbers):
    """Refuse positive indices that no ``record`` of the whole file defines (``numbers``: each
    face's line)."""
    bad = np.flatnonzero(np.any(F >= count, axis=1))
    if len(bad):
        f = bad[0]
        raise InvalidMeshError(f"{path} line {numbers[f]}: face uses {record} "
                               f"{int(F[f].max()) + 1}, but the file has {count} {record} "
                               f"record(s)")


def _first_use(names):
    """(m,) int64: each name's number in order of first appearance."""
    numbers = {}
    return np.asarray([numbers.setdefault(n, len(numbers)) for n in names], dtype=np.int64)


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
