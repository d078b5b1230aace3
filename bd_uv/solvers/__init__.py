"""Ways of finding a map in a bounded-distortion space.

- ``conic``: Clarabel's interior-point method on the whole conic program (the reference).
- ``projection``: projection iterations (Kovalsky et al. 2015): one factorisation, then per
  iteration a closed-form per-face projection and one back-solve; many islands at once.
- ``bound_search``: ``bound="auto"`` without a conic solve: ADMM onto F_C with frames (one
  factorisation for every C) and the search over C.
- ``flip_free``: a flip-free initial map near the LSCM map, by projection iterations.
- ``factor``: one sparse SPD factorisation, back-solved with several right-hand sides
  (cholespy, qdldl or scipy's SuperLU, whichever is installed).
- ``local_projection``: the closed-form per-face projection in the singular-value plane.

Every solver hands back an iterate; nothing here certifies it: the caller certifies every map from
its own UVs.
"""
