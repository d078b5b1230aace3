"""When projection iterations give up on a component: it stalls, or it is clearly out of reach.

Projection iterations (``projection.ProjectionSolver.project``) alternate between the maps and the
bounded-distortion set, whose faces' Jacobians form cones: scaling a map scales its distance to the
set. An island the bound cannot bend therefore keeps lowering its absolute distance to the set by
shrinking towards its fixed vertex, a few percent an iteration, while its max conformal distortion
(Lipman 2012, eq. 4.9) stays where it was (the 122-face shoulder of Khronos' RobotExpressive at
C = 5: distance 0.016 -> 3e-6 over 300 iterations, max distortion 9.6-10.9 throughout), and the
test on the absolute distance alone never fires: the iterations ran to their budget, 600 in all,
before the caller could fall back (cut seams, raise C, solve).

``Progress`` keeps both tests per component:

- **stalled** (the test of ``project``'s ``stall``): the area-weighted squared Frobenius distance
  of its Jacobians to the set has not dropped by 1 % over ``stall`` iterations;
- **out of reach**: over ``window`` iterations neither its distance relative to its size (the same
  distance over the area-weighted squared Frobenius norm of the projected Jacobians: scale-free,
  so shrinking does not count) dropped by ``progress`` of itself, nor its least max distortion by
  ``progress`` of its excess over C, while that least max is more than ``far`` times C.

Replayed on 1,300 traced projection runs (the disks, open and closed meshes of the shared set and
RobotExpressive's parts, under ``--seams needed`` at C = 1.5, 2 and 5, ``--seams auto``, ``--bound
auto`` with and without ``--stretch``, and single islands at C = 1.1-8 and at S = 1.2-3 with C up
to S^2): none of the 220 that certified went more than 3 iterations in a row without such progress
before it certified (the slowest took 190 iterations, under a stretch bound, progressing all the
way); 929 of the 1,080 that did not certify stop sooner, 97k iterations in all -> 43k. The shoulder's runs
stop after 54 and 52 iterations instead of 300.
"""
import numpy as np

__all__ = ["Progress", "REACH_FAR", "REACH_PROGRESS", "REACH_WINDOW"]

REACH_WINDOW = 20       # iterations without progress after which a component is out of reach
REACH_PROGRESS = 0.01   # progress: the relative distance down by this share of itself, or the
#                         least max distortion down by this share of its excess over C
REACH_FAR = 1.1         # ... only while the least max distortion is above this many times C
STALL_PROGRESS = 0.01   # the absolute distance down by this share of its least value


class Progress:
    """Per-component progress of projection iterations towards the bounded-distortion set.

    Parameters
    ----------
    C : float, the bound the components are certified at
    n : int, number of components
    stall : int, iterations without a 1 % drop of the absolute distance after which a component
        has stalled
    window : int or None, iterations without progress after which a component far above C is out
        of reach (None or 0: never)
    """

    def __init__(self, C, n, stall, window=REACH_WINDOW, progress=REACH_PROGRESS, far=REACH_FAR):
        self.C, self.stall, self.window = float(C), int(stall), int(window or 0)
        self.progress, self.far = float(progress), float(far)
        self.least_err = np.full(n, np.inf)     # least absolute distance, and when
        self.err_at = np.zeros(n, dtype=np.int64)
        self.least_rel = np.full(n, np.inf)     # relative distance at its last progress, and when
        self.rel_at = np.zeros(n, dtype=np.int64)
        self.least_max = np.full(n, np.inf)     # least max distortion so far
        self.max_mark = np.full(n, np.inf)      # ... at its last progress, and when
        self.max_at = np.zeros(n, dtype=np.int64)
        self.out_of_reach = np.zeros(n, dtype=bool)

    def update(self, it, err, size, max_distortion):
        """Record iteration ``it`` and return the components to stop, (n,) bool.

        Parameters
        ----------
        it : int
        err : (n,) float, area-weighted squared Frobenius distance of each component's Jacobians
            to the set
        size : (n,) float, area-weighted squared Frobenius norm of its projected Jacobians
        max_distortion : (n,) float, its max conformal distortion (inf where a face flips)

        Returns
        -------
        (n,) bool, stalled or out of reach (``out_of_reach`` says which were the latter)
        """
        p = self.progress
        down = err < self.least_err * (1.0 - STALL_PROGRESS)
        self.least_err = np.where(down, err, self.least_err)
        self.err_at = np.where(down, it, self.err_at)
        stop = it - self.err_at >= self.stall
        if not self.window:
            return stop
        with np.errstate(invalid="ignore", divide="ignore"):
            rel = np.where(size > 0, err / size, np.inf)
        down = rel < self.least_rel * (1.0 - p)
        self.least_rel = np.where(down, rel, self.least_rel)
        self.rel_at = np.where(down, it, self.rel_at)
        self.least_max = np.minimum(self.least_max, max_distortion)
        mark = self.max_mark
        with np.errstate(invalid="ignore"):
            down = (self.least_max < mark) & (
                ~np.isfinite(mark) | (self.least_max < mark - p * (mark - self.C)))
        self.max_mark = np.where(down, self.least_max, mark)
        self.max_at = np.where(down, it, self.max_at)
        far = (it - np.maximum(self.rel_at, self.max_at) >= self.window) & (
            self.least_max > self.far * self.C)
        self.out_of_reach |= far & ~stop
        return stop | far
