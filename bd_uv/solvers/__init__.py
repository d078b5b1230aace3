"""Ways of finding a map in a bounded-distortion space.

- ``conic``: Clarabel's interior-point method on the whole conic program (the reference).
- ``projection``: projection iterations (Kovalsky et al. 2015): one factorisation, then per
  iteration a closed-form per-face projection and one back-solve; many islands at once.
- ``flip_free``: a flip-free initial map near the LSCM map, by projection iterations.

Every solver hands back an iterate; nothing here certifies it: the caller certifies every map from
its own UVs.
"""
