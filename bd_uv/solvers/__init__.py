"""Ways of finding a map in a bounded-distortion space.

- ``conic``: Clarabel's interior-point method on the whole conic program (the reference).

Every solver hands back an iterate; nothing here certifies it: the caller certifies every map from
its own UVs.
"""
