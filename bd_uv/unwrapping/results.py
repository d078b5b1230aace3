"""What an unwrap returns: one result per island and the mesh's corner UVs."""
from dataclasses import dataclass, field

import numpy as np

from ..errors import BDError


@dataclass(frozen=True)
class IslandResult:
    """The outcome for one island; see docs/ARCHITECTURE.md for every field."""
    index: int
    faces: np.ndarray
    vertices: np.ndarray
    tris: np.ndarray
    uv: np.ndarray = None
    status: str = "failed"
    error: BDError = None
    message: str = ""
    bound_requested: object = None
    bound_certified: float = None
    max_distortion: float = float("nan")
    mean_distortion: float = float("nan")
    flipped: int = 0
    frames: str = ""
    energy: float = float("nan")
    seconds: float = 0.0
    solves: int = 0
    iterations: int = 0
    distortion: np.ndarray = None
    flags: tuple = ()
    timings: dict = field(default_factory=dict)
    overlap_free: bool = False
    min_singular: float = float("nan")
    max_singular: float = float("nan")
    cut_edges: np.ndarray = None
    cut_from: int = None
    bijective: bool = None

    def summary(self):
        """The island's entry in the JSON report."""
        def num(v):
            return None if v is None or not np.isfinite(v) else float(v)
        return {"island": self.index, "faces": int(len(self.faces)),
                "bound_requested": self.bound_requested,
                "bound_certified": num(self.bound_certified),
                "max_distortion": num(self.max_distortion),
                "mean_distortion": num(self.mean_distortion), "flipped": int(self.flipped),
                "frames": self.frames, "seconds": round(self.seconds, 4), "status": self.status,
                "solves": self.solves, "iterations": self.iterations, "flags": list(self.flags),
                "overlap_free": bool(self.overlap_free),
                "min_singular": num(self.min_singular), "max_singular": num(self.max_singular),
                "cut_edges": None if self.cut_edges is None else self.cut_edges.tolist(),
                "cut_from": self.cut_from,
                "bijective": self.bijective,
                "error": type(self.error).__name__ if self.error else None,
                "message": self.message,
                "timings": {k: round(v, 4) for k, v in self.timings.items()}}


@dataclass(frozen=True)
class UnwrapResult:
    """UVs of a whole mesh; ``corner_uv`` is NaN on faces of failed islands.

    With ``seams_mode="needed"`` (``bd_uv.seams.needed.unwrap_needed``):
    ``duplicate_of`` (m,) int64 or None: for a face left out of the solve as a duplicate
    (``bd_uv.repair``), the face it duplicates (-1 for the others). Such a face is in no
    island's ``faces``; its ``face_island`` and corner UVs are its twin's.
    ``seams_added`` (k,2) int64 or None: vertex pairs of the seams the search added.
    ``repair`` tuple of str: what was repaired before solving (``repair.Repair.notes``).
    ``atlas_cuts`` dict or None: of those seams, the ones added for the atlas
    (``bd_uv.seams.pack_shape``, ``UnwrapOptions.atlas_cuts``): ``cuts`` (bisections),
    ``length`` (3D length) and ``seams`` (k,2) int64 vertex pairs.

    ``certificates``: one ``certificate.Certificate`` per island (None for an island not
    certified), measured on ``corner_uv`` exactly as returned, when the unwrap kept them (it does
    unless it cut an island); ``layout.stored_layout`` reuses them instead of measuring the same
    UVs again. None otherwise (a result spliced by the seam search, for one).
    """
    corner_uv: np.ndarray
    face_island: np.ndarray
    islands: list
    seconds: float
    method: str
    duplicate_of: np.ndarray = None
    seams_added: np.ndarray = None
    repair: tuple = ()
    certificates: tuple = None
    atlas_cuts: dict = None

    @property
    def certified(self):
        return all(r.status == "certified" for r in self.islands)

    def vertex_uv(self):
        """UVs as one table per island vertex, for OBJ output.

        Returns
        -------
        uv : (K,2) float64, the certified islands' vertices in island order
        F_uv : (m,3) int64, index into uv of each face corner; -1 on faces of failed islands
        """
        uvs, F_uv, offset = [], np.full((len(self.face_island), 3), -1, dtype=np.int64), 0
        for r in self.islands:
            if r.status == "certified":
                uvs.append(r.uv)
                F_uv[r.faces] = r.tris + offset
                offset += len(r.uv)
        return (np.concatenate(uvs) if uvs else np.zeros((0, 2))), F_uv

    def seams_report(self):
        """``seams_added`` (vertex pairs), ``repair`` (sentences) and ``atlas_cuts`` (those
        seams added for the atlas: ``cuts``, ``length``, ``seams``) for the JSON report, when
        seams were added (``seams_mode="needed"`` or ``"auto"``); {} otherwise."""
        if self.seams_added is None:
            return {}
        out = {"seams_added": np.asarray(self.seams_added).tolist(), "repair": list(self.repair)}
        if self.atlas_cuts is not None:
            a = self.atlas_cuts
            out["atlas_cuts"] = {"cuts": int(a["cuts"]), "length": float(a["length"]),
                                 "seams": np.asarray(a["seams"]).tolist()}
        return out

    def report(self):
        """JSON-ready report: method, seconds and one entry per island."""
        return {"method": self.method, "seconds": round(self.seconds, 4),
                **self.seams_report(), "islands": [r.summary() for r in self.islands]}
