"""The live tool's island drawn in the UV editor, each triangle coloured by its distortion (the
paper's colours, ``bd_uv.distortion_colors``), redrawn with every frame.

``overlay_arrays`` (numpy only) builds what is drawn; ``DistortionOverlay`` hands it to the GPU
through a draw handler of the UV editor (not available without a window: headless tests check the
arrays).
"""
from __future__ import annotations

import numpy as np

import bpy

from .. import bd_uv

__all__ = ["overlay_arrays", "DistortionOverlay"]

ALPHA = 0.45     # the overlay's opacity: the UVs' wireframe stays readable through it


def overlay_arrays(corner_uv, distortion, bound):
    """Triangle positions and colours of the overlay.

    Parameters
    ----------
    corner_uv : (k,3,2) float, the island's triangles in UV space
    distortion : (k,) float, their conformal distortion
    bound : float C

    Returns
    -------
    pos : (3k,2) float32, col : (3k,4) float32 (each triangle's colour on its three corners)
    """
    col = np.asarray(bd_uv.distortion_colors(np.asarray(distortion, np.float64), bound),
                     dtype=np.float32)
    col[:, 3] = ALPHA
    pos = np.asarray(corner_uv, dtype=np.float32).reshape(-1, 2)
    return pos, np.repeat(col, 3, axis=0)


class DistortionOverlay:
    """A draw handler of the UV editor showing the latest frame (``update``) until ``remove``."""

    def __init__(self):
        import gpu                                      # needs a window (not in background mode)
        from gpu_extras.batch import batch_for_shader
        self._gpu, self._batch_for = gpu, batch_for_shader
        self._shader = gpu.shader.from_builtin('SMOOTH_COLOR')
        self._batch = None
        self._handle = bpy.types.SpaceImageEditor.draw_handler_add(self._draw, (), 'WINDOW',
                                                                   'POST_VIEW')

    def update(self, corner_uv, distortion, bound):
        pos, col = overlay_arrays(corner_uv, distortion, bound)
        self._batch = self._batch_for(self._shader, 'TRIS', {"pos": pos, "color": col})

    def _draw(self):
        if self._batch is None:
            return
        self._gpu.state.blend_set('ALPHA')
        self._batch.draw(self._shader)
        self._gpu.state.blend_set('NONE')

    def remove(self):
        if self._handle is not None:
            bpy.types.SpaceImageEditor.draw_handler_remove(self._handle, 'WINDOW')
            self._handle = None
