"""Colours for per-face conformal distortion, after Lipman 2012, section 6.1.

Grey means undistorted, red grows towards the bound; faces above 25 and 50 get their own colours
(green, blue), flipped faces are purple and degenerate faces yellow, so that neither can be
mistaken for an ordinary distorted face.
"""
import numpy as np

GREY = np.array([0.55, 0.55, 0.55, 1.0])
RED = np.array([0.75, 0.0, 0.0, 1.0])
ABOVE_25 = np.array([0.0, 0.7, 0.1, 1.0])
ABOVE_50 = np.array([0.05, 0.2, 0.95, 1.0])
FLIPPED = np.array([0.6, 0.0, 0.8, 1.0])
DEGENERATE = np.array([1.0, 0.9, 0.0, 1.0])


def distortion_colors(distortion, bound, flipped=None):
    """RGBA colour of each face from its conformal distortion.

    Parameters
    ----------
    distortion : (m,) float array
        Conformal distortion per face (``inf`` or NaN for flipped or degenerate faces).
    bound : float
        The distortion at which the grey-to-red ramp reaches full red (the bound C), > 1.
    flipped : (m,) bool array, optional
        Faces known to be flipped (purple). Without it every non-finite face counts as degenerate
        (yellow).

    Returns
    -------
    colors : (m,4) float64 array in [0, 1]
    """
    D = np.asarray(distortion, dtype=np.float64)
    bound = float(bound)
    finite = np.isfinite(D)
    span = max(bound - 1.0, 1e-12)
    t = np.clip(np.where(finite, (D - 1.0) / span, 0.0), 0.0, 1.0)[:, None]
    colors = (1.0 - t) * GREY + t * RED
    colors[finite & (D > 25.0)] = ABOVE_25
    colors[finite & (D > 50.0)] = ABOVE_50
    colors[~finite] = DEGENERATE
    if flipped is not None:
        colors[np.asarray(flipped, dtype=bool)] = FLIPPED
    return colors
