"""Unwrapping a mesh island by island: start maps, strategies, one conic problem per island, results.

- ``unwrap``: the entry point (``bd_uv.unwrap``);
- ``initial``: the map an island starts from and its frames;
- ``problem``: one island's normalised geometry, formulation and solve;
- ``strategies``: keep, bend, raise, minimise C, BD-ARAP;
- ``results``: ``IslandResult`` and ``UnwrapResult``.
"""
from .results import IslandResult, UnwrapResult
from .unwrap import unwrap
