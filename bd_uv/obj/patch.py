"""An OBJ file written back with new UVs: its own text, only the UVs replaced.

As a glTF or USD scene is patched rather than rebuilt (``bd_uv.scenes``), an unwrapped OBJ is
its input's text with every record kept in order (``v``, ``vn``, ``mtllib``, ``usemtl``, ``o``,
``g``, ``s``, comments, anything else, byte for byte) except the old ``vt`` records, replaced by
the new ones (in one block where the first ``vt`` or ``f`` record was), and the ``f`` records,
rewritten with the same vertex and normal indices (as written: a negative index stays) and the
new ``vt`` of each corner. A polygon stays one polygon when its triangles (``read.read_obj``'s,
``polygons.triangulate``) give each of its corners one ``vt``; else it is written as those
triangles, each with its own UVs, so the UVs per corner are the ones certified either way.
"""
import numpy as np

from ..errors import InvalidMeshError
from .text import COMMENT, obj_bytes, obj_records, obj_text


def polygon_corner_vt(polygons, F_vt, corners=None):
    """The ``vt`` of each polygon corner, from its fan triangles' corners.

    Parameters
    ----------
    polygons : (m,) int array, the polygon of each triangle (``read_obj``'s: polygon p's
        n - 2 triangles consecutive)
    F_vt : (m,3) int array, the ``vt`` of each triangle corner; -1 on triangles without UVs
    corners : (m,3) int array, optional, each triangle corner's place in its polygon
        (``read_obj``'s); default the fan from the first corner (triangle j: 0, j + 1, j + 2)

    Returns
    -------
    corner_vt : (c,) int64, the ``vt`` of each polygon corner (polygon p's at
        ``starts[p]:starts[p + 1]``), -1 where its polygon has none or is not whole
    starts : (P+1,) int64, the first corner of each polygon
    whole : (P,) bool, the polygon can be written as one: every triangle has UVs and those of
        a corner agree (one ``vt``), or no triangle has UVs
    """
    poly = np.asarray(polygons, dtype=np.int64).reshape(-1)
    F_vt = np.asarray(F_vt, dtype=np.int64).reshape(-1, 3)
    P = int(poly[-1]) + 1 if len(poly) else 0
    tris = np.bincount(poly, minlength=P)
    starts = np.concatenate([[0], np.cumsum(tris + 2)])
    corner = starts[poly][:, None] + _places(poly, starts, corners)
    lo = np.full(starts[-1], np.iinfo(np.int64).max)
    hi = np.full(starts[-1], -2, dtype=np.int64)
    np.minimum.at(lo, corner.ravel(), F_vt.ravel())
    np.maximum.at(hi, corner.ravel(), F_vt.ravel())
    with_uv = np.bincount(poly, weights=(F_vt >= 0).all(axis=1), minlength=P)
    owner = np.repeat(np.arange(P), tris + 2)
    agree = np.bincount(owner, weights=lo == hi, minlength=P) == tris + 2
    whole = (with_uv == 0) | ((with_uv == tris) & agree)
    corner_vt = np.where(whole[owner] & (lo >= 0), lo, -1)
    return corner_vt, starts, whole


def patched_obj(source, path, F, polygons, F_vt, uv, corners=None):
    """Write ``source``'s OBJ text to ``path`` with its UVs replaced by ``uv``.

    Parameters
    ----------
    source, path : str, the OBJ read and the file written (never the same)
    F : (m,3) int array, the faces as ``read_obj`` read ``source`` (its own vertex ids): the
        file is checked to still hold them
    polygons : (m,) int array, ``read_obj``'s polygon of each face
    F_vt : (m,3) int array, the row of ``uv`` at each face corner; -1 on faces written without
        UVs
    uv : (k,2) float array, the new ``vt`` records, written in order (float64, exactly)
    corners : (m,3) int array, optional, each face corner's place in its polygon
        (``read_obj``'s); default the fan from the first corner

    Returns
    -------
    int, the polygons written as their triangles (their triangles' UVs differ at a corner, or
    only some triangles have UVs)

    Raises
    ------
    InvalidMeshError when ``source`` no longer holds the faces ``F`` (changed since it was
    read): nothing is written.
    """
    F = np.asarray(F, dtype=np.int64).reshape(-1, 3)
    F_vt = np.asarray(F_vt, dtype=np.int64).reshape(-1, 3)
    corner_vt, starts, whole = polygon_corner_vt(polygons, F_vt, corners)
    local = _places(polygons, starts, corners)
    with open(source, "rb") as fh:
        text, encoding = obj_text(fh.read(), errors="surrogateescape")
    lines = text.splitlines(keepends=True)
    eol = (lines[0][len(lines[0].splitlines()[0]):] if lines else "") or "\n"
    block = "".join(f"vt {u!r} {v!r}{eol}" for u, v in np.asarray(uv, np.float64).tolist())
    # Python lists: read an element at a time below
    corner_list, start_list, whole_list = corner_vt.tolist(), starts.tolist(), whole.tolist()
    P = len(whole_list)
    out, placed, nv, p, seen = [], False, 0, 0, []   # seen: each polygon corner's v as read
    for number, record, raw in obj_records(text):
        body = COMMENT.sub("", record)
        tokens = body.split()
        key = tokens[0] if tokens else ""
        if key == "v":
            nv += 1
        if key in ("vt", "f") and not placed:    # the new UVs where the first of these was
            out.append(block)
            placed = True
        if key == "vt":
            continue
        if key not in ("f", "l") or (key == "l" and not any(
                len(t.split("/")) > 1 and t.split("/")[1] for t in tokens[1:])):
            out.append(raw)
            continue
        tail = record[len(body):] + _line_end(raw)      # the comment and the line end, kept
        items = [t.split("/") for t in tokens[1:]]
        if key == "l" or len(items) < 3:    # no polygon: its old vt indices dropped
            out.append(" ".join([key] + [_corner(it, -1) for it in items]) + tail)
            continue
        n = len(items)
        if p >= P or start_list[p + 1] - start_list[p] != n:
            raise _changed(source, path, number)
        try:
            seen += [i + nv if i < 0 else i - 1 for i in map(int, (it[0] for it in items))]
        except ValueError:
            raise _changed(source, path, number) from None
        if whole_list[p]:
            vts = corner_list[start_list[p]:start_list[p + 1]]
            out.append(" ".join(["f"] + [_corner(it, t) for it, t in zip(items, vts)]) + tail)
        else:   # its fan's triangles, each with its own UVs
            t0 = start_list[p] - 2 * p          # its first triangle
            fan = [" ".join(["f"] + [_corner(items[c], vt) for c, vt in
                                     zip(local[t0 + j].tolist(), F_vt[t0 + j].tolist())])
                   for j in range(n - 2)]
            out.append(eol.join(fan) + tail)
        p += 1
    # the faces read then are the faces the file holds now
    corner = starts[np.asarray(polygons, dtype=np.int64)][:, None] + local
    if p != P or not np.array_equal(np.asarray(seen, dtype=np.int64)[corner], F):
        raise _changed(source, path, None)
    with open(path, "wb") as fh:
        fh.write(obj_bytes("".join(out), encoding))
    return P - sum(whole_list)


def _changed(source, path, number):
    where = f"{source} line {number}" if number is not None else source
    return InvalidMeshError(f"{where}: the file changed since it was read; nothing was written "
                            f"to {path}")


def _places(polygons, starts, corners=None):
    """(m,3) int64: each triangle's corners' places in its polygon: ``corners``, or (None) the
    fans from the first corners."""
    if corners is not None:
        return np.asarray(corners, dtype=np.int64).reshape(-1, 3)
    poly = np.asarray(polygons, dtype=np.int64).reshape(-1)
    tris = np.diff(starts) - 2
    first = np.concatenate([[0], np.cumsum(tris)])[:-1]        # first triangle of each polygon
    j = np.arange(len(poly)) - first[poly]
    return np.stack([np.zeros_like(j), j + 1, j + 2], axis=1)


def _corner(item, vt):
    """A face corner ``v/vt/vn`` from its record's parts ``item`` (v and vn as written) and the
    new ``vt`` row (-1: none)."""
    vn = item[2] if len(item) > 2 else ""
    if vt >= 0:
        return f"{item[0]}/{vt + 1}" + (f"/{vn}" if vn else "")
    return f"{item[0]}//{vn}" if vn else item[0]


def _line_end(raw):
    """The line end of a record's last line (``raw``: its lines as the file has them)."""
    last = raw.splitlines(keepends=True)[-1]
    return last[len(last.splitlines()[0]):]
