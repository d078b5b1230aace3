"""What a format module hands over: one mesh of a scene as arrays (:class:`SceneMesh`), and
the certified UVs to write into it (:class:`Charts`)."""
from dataclasses import dataclass, field

import numpy as np


@dataclass(frozen=True)
class SceneMesh:
    """One mesh of a scene, as the unwrap sees it.

    Attributes
    ----------
    name : str, how the report names it (node paths, or the prim path)
    mesh : bd_uv.meshio.Mesh, V (n,3) float64 welded, F (m,3) int64, corner_uv (m,3,2) of the
        file's UVs (v upwards) or None
    info : dict, JSON-ready facts for the report (mesh name, nodes, primitives, ...)
    refused : str or None, why this mesh is left as it is (e.g. Draco-compressed)
    face_groups : (m,) int64 polygon of each triangle (seams never cross one), or None
    warnings : list of str
    """
    name: str
    mesh: object
    info: dict
    refused: str = None
    face_groups: np.ndarray = None
    warnings: list = field(default_factory=list)


@dataclass(frozen=True)
class Charts:
    """Certified UVs of one mesh to write.

    Attributes
    ----------
    corner_uv : (m,3,2) float64, v upwards (Blender's convention), every face written
    face_island : (m,) int64, stored island of each face; -1 for a face certified through
        others: zero-area (its neighbours' UVs) or a duplicate face (its twin's UVs)
    bounds : (k,) float64, the certified bound C of each stored island
    """
    corner_uv: np.ndarray
    face_island: np.ndarray
    bounds: np.ndarray
