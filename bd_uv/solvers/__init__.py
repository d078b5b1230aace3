"""Ways of finding a map in a bounded-distortion space.

- ``conic``: Clarabel's interior-point method on the whole conic program (the reference).
- ``ipm``: a primal-dual interior-point method that factorises only the Schur complement onto the
  vertex unknowns (same problem form and ``ConicSolution``; symbolic analysis reused, warm starts);
  ``cones`` holds its cone algebra and Nesterov-Todd scaling.

Every solver hands back an iterate; nothing here certifies it: the caller certifies every map from
its own UVs.
"""
