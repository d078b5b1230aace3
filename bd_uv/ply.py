"""Binary PLY files whose faces are lists of different lengths, which trimesh cannot read.

trimesh reads a binary PLY's face list as if every face had as many corners as the first, so a
file mixing triangles and quads (Rhino writes them so: draco's testdata/Box.ply) fails with "PLY
is unexpected length". Here the elements are walked in order: one without lists as a block of
numpy records, one with lists row by row. Only what the unwrap needs is kept: the vertices'
``x y z`` (and ``s t``, ``u v`` or ``texture_u texture_v``) and each face's corners (or a
``tristrips`` element's strips, as their triangles: trimesh reads such a file as no faces), polygons
triangulated (``polygons``: fans, concave polygons ear-clipped).
"""
import struct

import numpy as np

from .polygons import fan_triangles, triangulate

TYPES = {"char": "i1", "int8": "i1", "uchar": "u1", "uint8": "u1", "short": "i2",
         "int16": "i2", "ushort": "u2", "uint16": "u2", "int": "i4", "int32": "i4",
         "uint": "u4", "uint32": "u4", "float": "f4", "float32": "f4", "double": "f8",
         "float64": "f8"}
UV_NAMES = (("s", "t"), ("u", "v"), ("texture_u", "texture_v"), ("texture_s", "texture_t"))


def read_binary_ply(data):
    """(V (n,3) float64, F (m,3) int64, vertex UVs (n,2) float64 or None) of a binary PLY.

    Raises ValueError (with what is wrong) on a file it cannot read: an ASCII one, an unknown
    type, or data shorter than its header says.
    """
    head, sep, _ = data.partition(b"end_header")
    if not sep:
        raise ValueError("no end_header")
    start = len(head) + len(sep)
    start += 2 if data[start:start + 2] == b"\r\n" else 1
    lines = [ln.split() for ln in head.replace(b"\r", b"\n").split(b"\n")]
    lines = [[t.decode("latin-1") for t in ln] for ln in lines if ln]
    fmt = next((ln[1] for ln in lines if ln[0] == "format"), "")
    if fmt not in ("binary_little_endian", "binary_big_endian"):
        raise ValueError(f"format {fmt or 'missing'} is not binary")
    order = "<" if fmt == "binary_little_endian" else ">"
    elements = []
    for ln in lines:
        if ln[0] == "element":
            elements.append((ln[1], int(ln[2]), []))
        elif ln[0] == "property" and elements:
            if ln[1] == "list":
                elements[-1][2].append((ln[4], _type(ln[2]), _type(ln[3])))
            else:
                elements[-1][2].append((ln[2], _type(ln[1]), None))
    found, offset = {}, start
    for name, count, props in elements:
        if all(item is None for _, _, item in props):
            dtype = np.dtype([(p, order + t) for p, t, _ in props])
            if offset + dtype.itemsize * count > len(data):
                raise ValueError(f"element {name}: the data ends early")
            found[name] = np.frombuffer(data, dtype, count, offset)
            offset += dtype.itemsize * count
        else:
            found[name], offset = _rows(data, offset, count, props, order, name)
    if "face" not in found and "tristrips" in found:     # Cyberware's igea.ply: one long strip
        found["face"] = {"corners": _strip_triangles(found["tristrips"])}
    if "vertex" not in found or "face" not in found:
        raise ValueError("no vertex or no face element")
    vert = found["vertex"]
    if not {"x", "y", "z"} <= set(_names(vert)):
        raise ValueError("the vertices have no x, y and z")
    V = np.stack([np.asarray(vert[c], np.float64) for c in "xyz"], axis=1)
    uv = next((np.stack([np.asarray(vert[a], np.float64), np.asarray(vert[b], np.float64)], 1)
               for a, b in UV_NAMES if a in _names(vert) and b in _names(vert)), None)
    return V, _triangles(V, found["face"]), uv


def _type(name):
    try:
        return TYPES[name]
    except KeyError:
        raise ValueError(f"unknown property type {name!r}") from None


def _rows(data, offset, count, props, order, name):
    """An element with list properties read row by row: a structured array of its scalar
    properties and, for the corners, ``vertex_indices``/``vertex_index`` as a list of arrays."""
    scalars = [(p, t) for p, t, item in props if item is None]
    out = {p: np.empty(count, t) for p, t in scalars}
    corners = []
    try:
        for row in range(count):
            for p, t, item in props:
                if item is None:
                    (out[p][row],) = struct.unpack_from(order + _code(t), data, offset)
                    offset += np.dtype(t).itemsize
                else:
                    (n,) = struct.unpack_from(order + _code(t), data, offset)
                    offset += np.dtype(t).itemsize
                    size = np.dtype(item).itemsize * n
                    if offset + size > len(data):
                        raise struct.error("short")
                    values = np.frombuffer(data, order + item, n, offset)
                    offset += size
                    if p in ("vertex_indices", "vertex_index"):
                        corners.append(values.astype(np.int64))
    except struct.error:
        raise ValueError(f"element {name}: the data ends early") from None
    return {"corners": corners, **out}, offset


def _names(element):
    """The property names of an element read as records or row by row."""
    return element.keys() if isinstance(element, dict) else element.dtype.names


def _code(t):
    """The struct code of a numpy type string ("u1" -> "B")."""
    return np.dtype(t).char


def raw_polygons(mesh):
    """Each face's corners (a list of int64 arrays) of a PLY trimesh loaded, from the face
    element it keeps (``metadata["_ply_raw"]``: an ASCII file's lists as rows or arrays, a
    binary file's as (count, list) records), when a face has more than three: trimesh fans
    those from their first corner, a triangle outside a concave polygon or of no area where
    three corners lie in a line. None when every face is a triangle or the element is not
    there.

    Raises ValueError when a binary file's records hold a count other than their list's
    length: trimesh read every face as long as the first, which goes unnoticed when the
    lengths add up to as many bytes (three quads, a hexagon, a triangle with ten... : found by
    the polygon fuzz contract, garbage vertex ids), so the file is to be walked by
    ``read_binary_ply``."""
    try:
        data = mesh.metadata["_ply_raw"]["face"]["data"]
    except (AttributeError, KeyError, TypeError):
        return None
    name = next((n for n in ("vertex_indices", "vertex_index") if n in _names(data)), None)
    if name is None:
        return None
    lists = data[name]
    if getattr(lists, "dtype", None) is not None and lists.dtype.names:   # binary: (count, list)
        count, lists = lists[lists.dtype.names[0]], lists[lists.dtype.names[1]]
        if lists.ndim != 2 or (np.asarray(count) != lists.shape[1]).any():
            raise ValueError("face lists of different lengths read as one length")
    corners = [np.asarray(c, dtype=np.int64).reshape(-1) for c in lists]
    return corners if any(len(c) > 3 for c in corners) else None


def polygon_triangles(V, corners):
    """(m,3) int64: the triangles of polygons given as their corners' vertex ids (a list of
    arrays): each polygon's ``polygons.triangulate``'s (its fan, or its ears where concave)."""
    return _triangles(V, {"corners": corners})


def _triangles(V, faces):
    """(m,3) int64: each polygon's triangles (``polygons.triangulate``: its fan, or its ears
    where it is concave)."""
    corners = faces["corners"] if isinstance(faces, dict) else []
    corners = [c for c in corners if len(c) >= 3]
    if not corners:
        return np.zeros((0, 3), np.int64)
    flat = np.concatenate(corners).astype(np.int64)
    if len(flat) and (flat.min() < 0 or flat.max() >= len(V)):
        return flat[fan_triangles([len(c) for c in corners])[0]]   # named by the caller's check
    T = triangulate(V, [len(c) for c in corners], flat)[0]
    return flat[T]


def _strip_triangles(strips):
    """A ``tristrips`` element's strips (each list of vertex ids, -1 ending a strip) as the list
    of triangles they draw, each wound as the strip's first (every second one turned back), the
    triangles on a repeated vertex (the strips' joins) left out."""
    rows = strips["corners"] if isinstance(strips, dict) else []
    tris = []
    for ids in rows:
        ends = np.flatnonzero(ids < 0)
        for s in np.split(ids, ends):
            s = s[s >= 0]
            if len(s) < 3:
                continue
            i = np.arange(len(s) - 2)
            t = np.stack([s[i], s[i + 1], s[i + 2]], 1)
            odd = i % 2 == 1
            t[odd, 0], t[odd, 1] = s[i[odd] + 1], s[i[odd]]
            keep = (t[:, 0] != t[:, 1]) & (t[:, 1] != t[:, 2]) & (t[:, 0] != t[:, 2])
            tris.append(t[keep])
    return list(np.concatenate(tris)) if tris else []
