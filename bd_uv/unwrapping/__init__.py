"""Unwrapping a mesh island by island: start maps, strategies, one conic problem per island, results.

- ``unwrap``: the entry point (``bd_uv.unwrap``);
- ``one_disk``, ``disk_certificate``: a mesh that is one clean disk, found, solved and certified
  in one pass;
- ``initial``: the map an island starts from and its frames;
- ``problem``: one island's normalised geometry, formulation and solve;
- ``bounded``: keep, bend, raise a map for a given C, BD-ARAP;
- ``strategies``: minimise C (``bound="auto"``);
- ``finish``: an island's map scaled, placed and certified from its final UVs;
- ``results``: ``IslandResult`` and ``UnwrapResult``.
"""
from .results import IslandResult, UnwrapResult
from .unwrap import unwrap
