"""The best map on the segment between two maps, by golden section on ``u0 + s (u1 - u0)``,
s in [0, 1]: vectorised distortion evaluations only, no solve.

- ``strategies.best_along``: the least max distortion along a Dinkelbach step (it can overshoot
  where faces grew);
- ``bounded.bend``: the least mean distortion within C between the projected map and the bound
  search's map (three_peaks at C = 5: 1.378 at s = 0, 1.310 at s = 1, 1.304 near s = 0.7).
"""
import numpy as np


def golden(f, evaluations):
    """(s, f(s)) of the least value of ``f`` found on [0, 1] by golden section with
    ``evaluations`` (>= 2) evaluations; exact where f is unimodal (quasi-convex), else a point
    at least as good as the others evaluated."""
    g = 0.5 * (np.sqrt(5.0) - 1.0)
    a, b = 0.0, 1.0
    c, e = b - g * (b - a), a + g * (b - a)
    fc, fe = f(c), f(e)
    for _ in range(evaluations - 2):
        if fc < fe:
            b, e, fe = e, c, fc
            c = b - g * (b - a)
            fc = f(c)
        else:
            a, c, fc = c, e, fe
            e = a + g * (b - a)
            fe = f(e)
    return (c, fc) if fc < fe else (e, fe)


def least_mean_within(prob, u0, u1, C, evaluations):
    """The map of least area-weighted mean distortion on the segment from u0 to u1 among those
    whose max distortion is within C (``IslandProblem.check``), u0 and u1 included; u1 when no
    other is better. Both ends must be flip-free."""
    d = u1 - u0
    area = prob.ops.area / prob.ops.area.sum()

    def mean(s):
        D = prob.face_distortion(u0 + s * d)
        return float(area @ D) if D.max() <= C * (1 + 1e-9) else np.inf

    s, m = golden(mean, evaluations)
    best = (u1, mean(1.0))
    for t, mt in ((s, m), (0.0, mean(0.0))):
        if mt < best[1]:
            best = (u0 + t * d, mt)
    return best[0]
