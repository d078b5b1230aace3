"""The options of the atlas packer, in a texture artist's terms (one frozen dataclass)."""
from dataclasses import dataclass

from ..errors import PackError

ROTATIONS = ("none", "90", "any")


@dataclass(frozen=True)
class PackOptions:
    """How charts are packed into the texture square (or UDIM tiles).

    Attributes
    ----------
    resolution : int, texels along a side of the square (default 1024)
    padding_px : float, least gap between two charts in texels at ``resolution``, and half of it
        to the square's edge (default 4)
    texel_density : float or None, texels per scene unit for every chart; None (default): one
        density for every chart, as large as fits the square
    rotate : "none" | "90" | "any", the turns a chart may make (never a mirror)
    udim : bool, with ``texel_density``: charts that do not fit tile 1001 spill into 1002, 1003, ...
        (Blender's numbering: tile 1001 + u + 10 v covers [u, u+1] x [v, v+1])
    solve_seconds : int, time given to each nesting solve's search (spyrrow counts in whole
        seconds); 0 keeps its constructive placement only: tens of milliseconds a solve where 1
        takes a second, for a few points of coverage less (measured: a cube's 3 charts 0.655 in
        0.08 s against 0.654 in 3.9 s; cow's 46 charts 0.640 in 1.9 s against 0.661 in 5.0 s)
    solves : int, nesting solves spent on finding the smallest square (at least 1)
    seed : int, seed of the nesting heuristic. Its search is bounded in time, not in steps, so
        two runs on the same charts can give different layouts (each one certified); measured:
        suzanne's 27 charts, two runs, different placements
    """
    resolution: int = 1024
    padding_px: float = 4.0
    texel_density: float | None = None
    rotate: str = "any"
    udim: bool = False
    solve_seconds: int = 1
    solves: int = 3
    seed: int = 0

    def __post_init__(self):
        if not (isinstance(self.resolution, int) and 8 <= self.resolution <= 65536):
            raise PackError(f"resolution must be a whole number of texels from 8 to 65536, "
                            f"not {self.resolution!r}")
        if not 0 <= self.padding_px <= self.resolution / 8:
            raise PackError(f"padding must be from 0 to {self.resolution / 8:g} texels at "
                            f"{self.resolution} px, not {self.padding_px!r}")
        if self.texel_density is not None and not self.texel_density > 0:
            raise PackError(f"texel density must be a positive number of texels per scene "
                            f"unit, not {self.texel_density!r}")
        if self.rotate not in ROTATIONS:
            raise PackError(f"rotate must be one of {', '.join(ROTATIONS)}, not {self.rotate!r}")
        if self.udim and self.texel_density is None:
            raise PackError("UDIM tiles need a texel density: without one every chart is scaled "
                            "to fit tile 1001, so nothing would spill")
        if not (isinstance(self.solve_seconds, int) and self.solve_seconds >= 0):
            raise PackError(f"solve_seconds must be a whole number >= 0, not "
                            f"{self.solve_seconds!r}")
        if not (isinstance(self.solves, int) and self.solves >= 1):
            raise PackError(f"solves must be a whole number >= 1, not {self.solves!r}")

    @property
    def padding(self):
        """The padding as a fraction of a tile's side."""
        return self.padding_px / self.resolution

    def orientations(self):
        """spyrrow's allowed orientations in degrees (None: any angle)."""
        return {"none": [0.0], "90": [0.0, 90.0, 180.0, 270.0], "any": None}[self.rotate]


def udim_tile(index):
    """Blender's UDIM number of the ``index``-th tile (0 -> 1001) and its (u, v) offset."""
    return 1001 + index, (index % 10, index // 10)
