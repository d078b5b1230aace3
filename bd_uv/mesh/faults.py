"""Why an island cannot be parameterized, in the user's terms (faces and vertices named): the
first fault of its faces, in the order a user should fix them."""
import numpy as np

from ..errors import (DegenerateFacesError, DuplicateFacesError, NonFiniteError,
                      NonManifoldError, OrientationError)
from .arrays import TOO_LARGE, _some


def _repeated_rows(T):
    """(m,) bool: rows of the (m,3) int array ``T`` that occur more than once."""
    order = np.lexsort((T[:, 2], T[:, 1], T[:, 0]))
    S = T[order]
    same = np.all(S[1:] == S[:-1], axis=1)
    rep = np.zeros(len(T), dtype=bool)
    rep[1:] |= same
    rep[:-1] |= same
    out = np.empty(len(T), dtype=bool)
    out[order] = rep
    return out


def _validate(idx, faces, tris, vertices, V, degenerate, nonfinite, duplicate, nonmanifold,
              inconsistent, bowtie, label):
    """The first fault of island ``idx`` (its ``faces``), in the order a user should fix them: an
    IslandError naming the faces (a bow-tie: the vertices), or None."""
    name = f"island {idx}"
    # (the faulty faces' mask, the error, its advice from the count and the faces listed)
    first = [
        (nonfinite, NonFiniteError,
         lambda n, s: f"{n} face(s) have NaN or infinite vertex coordinates, or {TOO_LARGE} "
                      f"(faces {s}); fix or delete those vertices"),
        (duplicate, DuplicateFacesError,
         lambda n, s: f"{n} faces repeat the same three vertices (faces {s}); merge or delete "
                      "the duplicates"),
        (nonmanifold, NonManifoldError,
         lambda n, s: f"non-manifold edges (shared by 3 or more faces) at faces {s}; split "
                      "those edges or mark them as seams")]
    then = [
        (inconsistent, OrientationError,
         lambda n, s: f"{n} faces are oriented against their neighbours (faces {s}); "
                      "recalculate normals (Mesh > Normals > Recalculate Outside)"),
        (degenerate, DegenerateFacesError,
         lambda n, s: f"{n} zero-area face(s) (faces {s}); dissolve degenerate geometry "
                      "(Mesh > Clean Up > Degenerate Dissolve)")]
    fault = _first_fault(name, idx, faces, first)
    if fault is not None:
        return fault
    bv = bowtie[bowtie[:, 1] == label, 0] if len(bowtie) else np.zeros(0, np.int64)
    if len(bv):
        bad = faces[np.isin(vertices[tris], bv).any(axis=1)]
        return NonManifoldError(f"{name}: non-manifold vertex (faces meet only at a point) at "
                                f"vertices {_some(bv)}; split the vertex (Mesh > Split) or "
                                "separate the parts", idx, bad)
    return _first_fault(name, idx, faces, then)


def _first_fault(name, idx, faces, checks):
    """The error of the first check (mask, error class, advice) some of ``faces`` fail, or None."""
    for mask, error, advice in checks:  # per kind of fault, in order
        bad = faces[mask[faces]]
        if len(bad):
            return error(f"{name}: {advice(len(bad), _some(bad))}", idx, bad)
    return None
