"""One target's iterations of ``bound_search``, watched: the least max distortion so far, when to
stop (the target reached, or out of reach), and whether the search's ``enough`` accepts an
iterate (``ready`` first: a cheap test it needs).

Split from ``bound_search`` (the search over C and its ADMM), with the constants of the stop.
"""
import numpy as np

__all__ = ["Watch", "ask"]

MAX_ITER = 150      # iterations per target
# A target is out of reach after STALL iterations that did not lower the max by PROGRESS of its
# excess over 1 (20 -> 12: nefertiti 125 -> 80 iterations, C 1.2640 -> 1.2653; hemisphere 156 ->
# 127, 1.03528 -> 1.03529; mushroom 72 -> 48; three_peaks 181 -> 127, 2.049 -> 2.075; at 8
# hemisphere stopped at 1.0389, above the lowest peer's 1.037)
STALL = 12          # a target is out of reach after this many iterations ...
PROGRESS = 0.01     # ... that did not lower the max by this share of its excess over 1,
FLIPPING = 6        # or after this many flipping iterates in a row from its start


class Watch:
    """One target's iterations watched: the least max distortion so far (``best``), and when
    to stop. Out of reach: no progress for STALL iterations, or FLIPPING flipping iterates in a
    row from the start (three_peaks: a target that flips stays flipped)."""

    def __init__(self, best, ask=None):
        self.best, self.since, self.mark = best, 0, best
        self.ask, self.ended, self.refused, self.pending = ask, False, False, False

    def accepts(self, kept):
        """Is the new best iterate ``kept`` enough (the search ends there)? ``ask(kept)`` (the
        search's ``ready``, then its ``enough``): True, False (then not asked again in this
        target: the search asks the target's best at its end, ``pending``), or None (``ready``
        refused it)."""
        if self.ask is None or self.refused:
            self.pending = True
            return False
        answer = self.ask(kept)
        self.pending, self.refused, self.ended = False, answer is False, answer is True
        return self.ended

    def seen(self, D, it, C):
        """(better, stop) after iteration ``it`` (>= 1) reached the max distortion D."""
        better = D < self.best
        if better:
            self.best = D
            if D <= C:
                return True, True
        if D < self.mark - PROGRESS * (self.mark - 1.0):
            self.since, self.mark = 0, D
        else:
            self.since += 1
            if self.since >= (FLIPPING if D == np.inf and self.since == it else STALL):
                return better, True
        return better, it == MAX_ITER

    def iterate(self, step, measure, keep, C, cancel):
        """``step()`` up to MAX_ITER times; before each but the first, ``measure()`` the max
        distortion, ``kept = keep()`` (a copy of the iterate) when it is the least yet, and stop
        when ``seen`` says so or ``cancel`` is set."""
        self.kept = None
        for it in range(MAX_ITER + 1):
            if cancel is not None and cancel.is_set():
                break
            if it:
                better, stop = self.seen(measure(), it, C)
                if better:
                    self.kept = keep()
                    if self.accepts(self.kept):
                        break
                if stop:
                    break
            step()


def ask(enough, ready, u):
    """``enough(u)`` where ``ready(u)`` (None: either is missing), else None."""
    return enough(u) if ready is None or ready(u) else None
