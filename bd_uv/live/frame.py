"""What a live session gives back: ``LiveFrame``, one certified frame, and the error a closed
session raises (``session.LiveSession``)."""
from dataclasses import dataclass

import numpy as np

from ..errors import BDError


class SessionClosedError(BDError):
    """The live session was closed; start a new one."""


@dataclass(frozen=True)
class LiveFrame:
    """One certified frame of a live session.

    Attributes
    ----------
    uv : (n,2) float64, the island's positions; pins on their targets when ``pin_error`` is 0
    certified : bool, True: 0 flips, max distortion <= C against the rest shape, no overlap,
        all from ``uv`` itself
    max_distortion : float
    flipped : int (0)
    overlaps : int (0): crossing boundary segment pairs and loops on the wrong side
    pin_error : float, largest distance from a pin to its target
    seconds : float, wall time of the update
    iterations : int, local/global and projection steps taken
    distortion : (k,) float64, per face against the rest shape (for colouring)
    """
    uv: np.ndarray
    certified: bool
    max_distortion: float
    flipped: int
    overlaps: int
    pin_error: float
    seconds: float
    iterations: int
    distortion: np.ndarray
