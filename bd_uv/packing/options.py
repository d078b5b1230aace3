"""The options of the atlas packer, in a texture artist's terms (one frozen dataclass)."""
from dataclasses import dataclass

import numpy as np

from ..errors import PackError

ROTATIONS = ("none", "90", "any")
GROUPINGS = ("none", "object", "material")
# The adaptive time: about a sixth of what Blender 5's exact-shape packer takes on the same
# charts on an idle machine. Its time went about as 0.0145-0.024 s sqrt(charts x faces) there
# (2026-11-27, load ~1, bench_pack: suzanne 27 charts 968 faces 2.97 s, cow 45/5804 10.4 s, dino
# 36/7828 12.9 s, camel 29/19536 10.9 s, ChineseDragon 116/19994 31.8 s): 2-2.5x faster than the
# same packer on a loaded machine (0.045 s; suzanne 7.3 s, cow 28.9 s), since it uses every core,
# while this budget is CPU seconds. At 0.006 a root, 0.08 a chart and at least 0.6 s the idle
# machine's runs took 0.24-0.28x Blender's time on suzanne, cow, camel and ChineseDragon; at
# these 0.12-0.16x, with the same coverage on suzanne, cow and camel (3 seeds) and a few points
# less on dino and ChineseDragon. A chart count or a face count alone does not follow Blender's
# time (dino has more faces than cow and takes less time).
AUTO_SECONDS_PER_ROOT = 0.004   # seconds per sqrt(charts x faces)
# and at most this much a chart: the root alone overshot on meshes of many faces in few charts
# (camel: 29 charts of 19.5k faces, Blender 0.38 s a chart)
AUTO_SECONDS_PER_CHART = 0.06
AUTO_SECONDS_MAX = 20.0
# and at least this much (two charts or more): on eight's 6 charts (634 faces) the root gave
# 0.37 s and coverage 0.558 (8 seeds, load ~8); 0.6 s gave 0.586. Blender's exact-shape packer
# took at least 2.8 s on every mesh measured (eight 2.8 s idle, 6.4 s loaded)
AUTO_SECONDS_MIN = 0.5
# but no more than this a chart below six charts: Blender's exact shape takes 0.8-1.6 s a chart
# on so few (quiet, 2026-11-27: fandisk's 4 charts 3.2 s, Blender's UV sphere's 3 charts 4.7 s),
# and 0.6 s for fandisk's 4 was 0.217x its time; 0.4 s reached the same coverage (0.663-0.664,
# 3 seeds), 0.3 s for the sphere's 3 charts too (0.713-0.717)
AUTO_SECONDS_MIN_PER_CHART = 0.1
# and, up to DOMINANT_MAX_CHARTS charts, times DOMINANT_SHARE / s where the largest chart holds a
# share s of the charts' area above DOMINANT_SHARE: the layout is then mostly where that chart
# goes. Measured (issue18-packtime13-2026-11-28.md, seeds 0-11, with the coarse nesting of
# .square): rocker-arm's 10 charts (largest 0.43; 0.6 -> 0.42 s, the one set above 0.2x
# Blender's exact-shape time at 0.6 s) 0.620 -> 0.631 against main; Blender's monkey's 6 charts
# (0.41) 0.615 -> 0.616; the Utah teapot's 12 (0.39) 0.631 at the full time and 0.639 at 0.75x
# (the same minutes; it loses to main by the coarse nesting, see .square). A stronger cut lost
# 0.003-0.01 on all three (0.85x of this: rocker-arm 0.630 -> 0.621)
DOMINANT_SHARE = 0.3
DOMINANT_MAX_CHARTS = 30
# Where AUTO_SECONDS_PER_CHART cut the time (many faces in each chart) and no chart dominates, the
# nesting may take REACH times its share, its density guessed for that search, each search ending
# once its layout is square (.square, .early_stop): the cut matches Blender's time on some such
# meshes (igl-arm 2.8 s) and not on others (igl-elephant 12.6 s, homer 10.3 s, cheburashka 6.8 s),
# and nothing in the outlines told them apart. Measured (issue18-pack24-2026-11-28.md, CPU, load
# 9-14): at 3x, 10 such sets against main +0.0217 coverage (se 0.0040; 24 wins, 6 losses; camel
# -0.006, knight -0.005) at 19 % more CPU, igl-elephant 0.690 -> 0.725 (0.80 -> 1.04 s), igl-arm
# 0.668 -> 0.717 (0.82 -> 1.27 s: its time, 0.2x Blender's, fails either way); at 4x the guess
# reaches GUESS_MAX on them: igl-elephant 0.720 -> 0.740 (1.00 -> 1.27 s), cheburashka 0.723 ->
# 0.743, fancyteapot 0.698 -> 0.721, homer the same; 5x as 4x. But idle (lead, 19:05, seeds 0-2,
# pack.seconds by the clock) 4x ran igl-arm's searches to their end, 2.98-3.20 s (Blender 3.08 s:
# 0.92x in bench_pack, against 0.30x), where 3x took 0.89-1.81 s (main 0.96-1.14) at 0.710-0.724
# (main 0.674-0.689) and igl-elephant 0.711-0.741 in 0.86-1.11 s (4x: 0.731-0.744 in 1.19-1.75 s;
# main 0.675-0.700); 2x: arm 0.679-0.696, elephant 0.683-0.719 (short of its 0.719). At 3x
# cheburashka 0.701-0.723 in 0.73-0.86 s (main 0.690-0.700, 0.78-1.26 s), fancyteapot 0.706-0.717
# in 1.35-1.47 s (main 0.653-0.700, 0.65-0.99 s), homer as main
REACH = 3.0
# ... and DOMINANT_REACH times it where one chart holds more than DOMINANT_SHARE (its time cut by
# that share too; the density guessed for the longer search, each search ended at its square).
# Measured (issue18-pack26-2026-11-28.md, interleaved per seed): rocker-arm's 10 charts (0.43)
# at load 1.5-1.9, seeds 0-5: 0.626 -> 0.673 (6/6, min 0.595 -> 0.657; pack.seconds 0.66 -> 0.86
# s against Blender's 5.5 s idle); under load, where the clock-bounded search is starved, even:
# load 3.5 -0.012 (1/3, 4 seeds), load 4-10 +0.001 (5/4, 10 seeds); spot's 12 charts (0.32)
# +0.004 (10 seeds, load 4-10) and -0.006 (4, load 3.4), igl-screwdriver's 10 +0.000 and +0.003,
# lion-head's 9 +0.003 (10); 2 instead of 3: rocker-arm 0.633 (its density guess barely moves)
DOMINANT_REACH = 3.0
# From MANY_CHARTS charts that are not tiny (``tiny``: under packing.tiny's TINY_SHARE of the
# area each), the time is at least MANY_SECONDS_PER_CHART a chart that is not tiny. Blender's
# exact-shape time follows the count of charts it must trace and scan for (its rasters: O(n^3) by
# its own note), not their faces: on low-poly assets of many charts the root above gives little (the
# Spider's 63 charts of 1,368 faces: 1.17 s, Blender 42-130 s at load 6-14). Measured
# (issue18-many24-2026-11-28.md, seeds 0-3, load ~9, with large_first's second nesting): the
# Spider (54 not tiny) at 2.2 s 0.652 -> 0.688 (4/4). Wuson's 83 charts (56 tiny: Blender 25-32 s
# at load 5-10, 8.2-8.7 s at load 3-5) keep the root; since pack25 they go to .tiny (67 % tiny),
# which nests the 27 others for their own count's time. 0.04 -> 0.064 (issue18-pack26-2026-11-28.md,
# interleaved per seed under load): Spider 0.674 -> 0.698 (4/4) and 0.653 -> 0.687 (3/1), CPU
# 2.4 -> 3.2 s against Blender's 29.4 s idle; max3ds (68 not tiny) 0.653 -> 0.668 (3/1)
MANY_CHARTS = 40
MANY_SECONDS_PER_CHART = 0.064
# Where the root sets the time (above the floor, under the per-chart cut: fewer than
# (AUTO_SECONDS_PER_CHART / AUTO_SECONDS_PER_ROOT)^2 = 225 faces a chart) on up to
# ROOT_GAIN_MAX_CHARTS charts, the packing takes ROOT_GAIN times it. Blender's exact-shape time
# on such sets went as 0.032-0.037 s a root (the lead's idle benches, 2026-11-29: suzanne 27
# charts 5.1-5.5 s, dino 36 charts 19.2-20.6 s, cow 45 charts 18.8-21.2 s), so the root gave them
# 0.10-0.13x of it, where sets of few charts of many faces (cut per chart) took 0.15-0.22x
# (rocker-arm, igl-arm), and their coverage was the one at the 1.05x line. Measured
# (issue18-pack29-2026-11-29.md, interleaved per seed, load 4-7): 1.3x: dino 0.667 -> 0.681
# (9 wins, 2 losses, 12 seeds; CPU 2.27 -> 2.91 s), suzanne 0.591 -> 0.604 (10/2; 0.82 -> 0.88
# s), cow 0.702 -> 0.708 (4/1, 6 seeds; 1.95 -> 2.15 s); 1.5x about as much for more time, its
# nesting (dino +0.025) or its compaction (suzanne +0.013) alone too. Not above 50 charts:
# ChineseDragon's 116 (Blender 0.021 s a root) already take about 0.2x
ROOT_GAIN = 1.3
ROOT_GAIN_MAX_CHARTS = 50


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
    solve_seconds : float or None, seconds the nesting may take to find the smallest square
        (its solves' first placements, about 15 ms a chart each, are measured and left out of
        their search); None (default): adaptive (:meth:`search_seconds`); 0 keeps spyrrow's
        first placements only, for a few points of coverage less. 2-5 charts are laid out
        without spyrrow (:mod:`.few`); a number here (or ``solves`` above 1) nests them too and
        keeps the smaller square
    solves : int, nesting solves for the smallest square (at least 1; default 1: one solve at
        a guessed density, then compaction, :mod:`.compact`); above 1, two rounds:
        (solves + 1) // 2 at once (threads) at strip heights around the guess, then solves // 2
        around the density reached (each solve pays its first placement again)
    group : "none" | "object" | "material", charts of one object (or one material) packed together:
        one compact block per group, blocks apart by the padding (:mod:`.groups`); "none"
        (default) packs every chart freely
    seed : int, seed of the nesting heuristic. Its search is bounded in time, not in steps, so
        two runs on the same charts can give different layouts (each one certified); measured:
        suzanne's 27 charts, two runs, different placements
    """
    resolution: int = 1024
    padding_px: float = 4.0
    texel_density: float | None = None
    rotate: str = "any"
    udim: bool = False
    solve_seconds: float | None = None
    solves: int = 1
    group: str = "none"
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
        if self.solve_seconds is not None and not (
                isinstance(self.solve_seconds, (int, float)) and 0 <= self.solve_seconds <= 3600):
            raise PackError(f"solve_seconds must be a number of seconds from 0 to 3600 (or "
                            f"None: adaptive), not {self.solve_seconds!r}")
        if self.group not in GROUPINGS:
            raise PackError(f"group must be one of {', '.join(GROUPINGS)}, not {self.group!r}")
        if not (isinstance(self.solves, int) and self.solves >= 1):
            raise PackError(f"solves must be a whole number >= 1, not {self.solves!r}")

    def search_seconds(self, charts, faces=0, largest=0.0, tiny=0):
        """Seconds of nesting for ``charts`` charts of ``faces`` faces: ``solve_seconds``, or
        adaptive: ``AUTO_SECONDS_PER_ROOT`` sqrt(charts x faces), at most
        ``AUTO_SECONDS_PER_CHART`` a chart and ``AUTO_SECONDS_MAX``, at least
        ``AUTO_SECONDS_MIN`` or ``AUTO_SECONDS_MIN_PER_CHART`` a chart, the less (0 for one
        chart); up to ``DOMINANT_MAX_CHARTS`` charts, times ``DOMINANT_SHARE`` / ``largest``
        where the largest chart's share of the charts' area, ``largest``, is above
        ``DOMINANT_SHARE``; from ``MANY_CHARTS`` charts that are not among the ``tiny`` ones,
        at least ``MANY_SECONDS_PER_CHART`` each (at most ``AUTO_SECONDS_MAX``)."""
        if self.solve_seconds is not None:
            return float(self.solve_seconds)
        if charts < 2:
            return 0.0
        seconds = max(min(AUTO_SECONDS_PER_ROOT * float(np.sqrt(charts * max(faces, charts))),
                          AUTO_SECONDS_PER_CHART * charts, AUTO_SECONDS_MAX),
                      min(AUTO_SECONDS_MIN, AUTO_SECONDS_MIN_PER_CHART * charts))
        if charts <= DOMINANT_MAX_CHARTS and largest > DOMINANT_SHARE:
            seconds *= DOMINANT_SHARE / largest
        if charts - tiny >= MANY_CHARTS:
            seconds = max(seconds, min(MANY_SECONDS_PER_CHART * (charts - tiny),
                                       AUTO_SECONDS_MAX))
        return seconds

    def reach(self, charts, faces=0, largest=0.0):
        """``REACH`` where the adaptive time of :meth:`search_seconds` is cut by
        ``AUTO_SECONDS_PER_CHART`` and no chart holds more than ``DOMINANT_SHARE`` of the area,
        with one solve (only a single solve can be ended early: :mod:`.early_stop`); else 1."""
        if charts <= DOMINANT_MAX_CHARTS and largest > DOMINANT_SHARE:
            return 1.0
        return REACH if self._cut_sets_time(charts, faces) else 1.0

    def dominant_reach(self, charts, faces=0, largest=0.0):
        """``DOMINANT_REACH`` where the time is cut as for :meth:`reach` but one chart holds
        more than ``DOMINANT_SHARE`` of the area (up to ``DOMINANT_MAX_CHARTS`` charts: the
        time already cut by that share); else 1."""
        if not (charts <= DOMINANT_MAX_CHARTS and largest > DOMINANT_SHARE):
            return 1.0
        return DOMINANT_REACH if self._cut_sets_time(charts, faces) else 1.0

    def root_gain(self, charts, faces=0):
        """``ROOT_GAIN`` where the root ``AUTO_SECONDS_PER_ROOT`` sqrt(charts x faces) sets the
        adaptive time (above its floor, at most ``AUTO_SECONDS_PER_CHART`` a chart, under
        ``AUTO_SECONDS_MAX``) on up to ``ROOT_GAIN_MAX_CHARTS`` charts, with one solve and no
        time given; else 1. The packing takes that many times :meth:`search_seconds`."""
        if (self.solve_seconds is not None or self.solves > 1
                or not 2 <= charts <= ROOT_GAIN_MAX_CHARTS):
            return 1.0
        root = AUTO_SECONDS_PER_ROOT * float(np.sqrt(charts * max(faces, charts)))
        floor = min(AUTO_SECONDS_MIN, AUTO_SECONDS_MIN_PER_CHART * charts)
        return ROOT_GAIN if floor < root <= AUTO_SECONDS_PER_CHART * charts and \
            root < AUTO_SECONDS_MAX else 1.0

    def _cut_sets_time(self, charts, faces):
        """Whether the adaptive time is cut by ``AUTO_SECONDS_PER_CHART`` (above the floor),
        with one solve and no time given."""
        if self.solve_seconds is not None or self.solves > 1 or charts < 2:
            return False
        root = AUTO_SECONDS_PER_ROOT * float(np.sqrt(charts * max(faces, charts)))
        cut = AUTO_SECONDS_PER_CHART * charts
        return cut < min(root, AUTO_SECONDS_MAX) and cut > min(
            AUTO_SECONDS_MIN, AUTO_SECONDS_MIN_PER_CHART * charts)

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
