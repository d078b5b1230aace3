"""Reading an OBJ file's text: ``v``, ``vt`` and ``f`` records, ``usemtl`` and ``o`` names.

OBJ is read by position index (``v`` records) so vertex order is the file's own; loaders that
split vertices at UV seams would change the topology. Polygons are triangulated
(``polygons.triangulate``: fans where sound, else turned fans or ears); negative
indices count back from the records read before the face; a line ending in a backslash goes on
on the next; UTF-8 (with or without a byte order mark) or UTF-16 after its mark.
"""
import numpy as np

from ..errors import InvalidMeshError
from ..polygons import triangulate
from .text import COMMENT, obj_records, obj_text


def read_obj(path):
    """V, F, corner UVs or None, each face's material (``usemtl``) and object (``o``), each
    numbered in order of first use by a face (faces before any ``usemtl`` or ``o`` make a
    material or object of their own), each face's polygon, (m,) int64: the ``f`` record (with
    three corners or more) it is a triangle of, numbered in file order, and each face's corners'
    places in its polygon, (m,3) int64: a polygon of n corners gives n - 2 consecutive faces,
    the fan from its first corner, or where that fan has a triangle with no area or outside the
    polygon, from another corner or its ears (``polygons.triangulate``).

    A negative index counts back from the last ``v`` (``vt``) read before its face, as the OBJ
    format defines it (files written object by object use ``f -4 -3 -2 -1``). Records may be
    separated by tabs; a file starting with a UTF-16 byte order mark is read as UTF-16. An
    index naming no vertex is an ``InvalidMeshError`` giving the file's line."""
    vs, vts, corner_v, corner_t, sizes, mats, objs, numbers = [], [], [], [], [], [], [], []
    mat, obj = None, None
    with open(path, "rb") as fh:
        text, _ = obj_text(fh.read())
    for number, line, _ in obj_records(text):
        line = COMMENT.sub("", line)   # "f 1 2 3 # note": a comment ends a record
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
            corner_v += [_obj_index(path, number, it[0], len(vs), "v") for it in items]
            corner_t += [_obj_index(path, number, it[1], len(vts), "vt") + 1
                         if len(it) > 1 and it[1] else 0 for it in items]
            sizes.append(len(items))
            mats.append(mat)
            objs.append(obj)
            numbers.append(number)
    V = _numbers(path, vs, "v", 3)
    corner_v = np.asarray(corner_v, dtype=np.int64)
    corner_t = np.asarray(corner_t, dtype=np.int64)            # 1-based; 0: no vt
    starts = np.concatenate([[0], np.cumsum(sizes, dtype=np.int64)])
    lines = np.asarray(numbers, dtype=np.int64)                # each polygon's line
    if len(sizes):   # the largest index of each polygon: one the file defines
        _check_forward(path, np.maximum.reduceat(corner_v, starts[:-1])[:, None], len(V), "v",
                       lines)
    T, polygon, _ = triangulate(V, np.diff(starts), corner_v)  # fans, else turned fans or ears
    corners = T - starts[polygon][:, None]                     # places in each polygon
    at = starts[polygon][:, None] + corners
    F, T = corner_v[at].reshape(-1, 3), corner_t[at].reshape(-1, 3)
    numbers = lines[polygon]                                   # each face's line
    cuv = None
    if len(vts) and len(T) and np.all(T != 0):
        VT = _numbers(path, vts, "vt", 2)
        _check_forward(path, T - 1, len(VT), "vt", numbers)
        cuv = VT[T - 1]
    labels = {"material": _first_use(mats)[polygon], "object": _first_use(objs)[polygon]}
    return V, F, cuv, labels, polygon, corners


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
