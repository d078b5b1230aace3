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
    name = f"island {idx}"
    bad = faces[nonfinite[faces]]
    if len(bad):
        return NonFiniteError(f"{name}: {len(bad)} face(s) have NaN or infinite vertex coordinates, "
                              f"or {TOO_LARGE} (faces {_some(bad)}); fix or delete those "
                              "vertices", idx, bad)
    bad = faces[duplicate[faces]]
    if len(bad):
        return DuplicateFacesError(f"{name}: {len(bad)} faces repeat the same three vertices "
                                   f"(faces {_some(bad)}); merge or delete the duplicates",
                                   idx, bad)
    bad = faces[nonmanifold[faces]]
    if len(bad):
        return NonManifoldError(f"{name}: non-manifold edges (shared by 3 or more faces) at faces "
                                f"{_some(bad)}; split those edges or mark them as seams", idx, bad)
    bv = bowtie[bowtie[:, 1] == label, 0] if len(bowtie) else np.zeros(0, np.int64)
    if len(bv):
        bad = faces[np.isin(vertices[tris], bv).any(axis=1)]
        return NonManifoldError(f"{name}: non-manifold vertex (faces meet only at a point) at "
                                f"vertices {_some(bv)}; split the vertex (Mesh > Split) or "
                                "separate the parts", idx, bad)
    bad = faces[inconsistent[faces]]
    if len(bad):
        return OrientationError(f"{name}: {len(bad)} faces are oriented against their neighbours "
                                f"(faces {_some(bad)}); recalculate normals (Mesh > Normals > "
                                "Recalculate Outside)", idx, bad)
    bad = faces[degenerate[faces]]
    if len(bad):
        return DegenerateFacesError(f"{name}: {len(bad)} zero-area face(s) (faces {_some(bad)}); "
                                    "dissolve degenerate geometry (Mesh > Clean Up > Degenerate "
                                    "Dissolve)", idx, bad)
    return None
