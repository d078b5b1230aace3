"""``disk_certificate.measure_disk`` writes out ``metrics._distortion`` of the signed UV areas
(no np.errstate, no calls): each face's distortion must be metrics' bit for bit, flipped,
collapsed, degenerate and non-finite faces included, and the singular values' range too."""
import numpy as np

from bd_uv.geometry import gradient_operators, local_coordinates
from bd_uv.metrics import _distortion, signed_uv_areas
from bd_uv.unwrapping.disk_certificate import measure_disk
from helpers import grid


def test_the_written_out_distortion_is_metrics_to_the_bit():
    V, F = grid(9, 7, lambda x, y: 0.3 * np.sin(3 * x) * np.cos(2 * y))
    G = gradient_operators(local_coordinates(V, F))
    rng = np.random.default_rng(5)
    for trial in range(40):
        uv = V[:, :2] * rng.uniform(0.5, 2.0) + rng.normal(0, 0.02 * (trial % 4), V[:, :2].shape)
        corner_uv = uv[F].copy()
        if trial % 5 == 1:
            corner_uv[3] = corner_uv[3, ::-1]               # a flipped face
        if trial % 5 == 2:
            corner_uv[7, 2] = corner_uv[7, 0]               # a collapsed face
        if trial % 5 == 3:
            corner_uv[11, 1, 0] = np.nan
        if trial % 5 == 4:
            corner_uv[13, 1, 1] = np.inf
        with np.errstate(all="ignore"):     # inf and NaN corners warn in either's products
            D, smin, smax = measure_disk(corner_uv, G)
            d = corner_uv - corner_uv[:, :1]
            gx = np.einsum("mkc,mc->mk", G, d[:, :, 0])
            gy = np.einsum("mkc,mc->mk", G, d[:, :, 1])
            a = np.abs(0.5 * ((gx[:, 0] + gy[:, 1]) + 1j * (gy[:, 0] - gx[:, 1])))
            b = np.abs(0.5 * ((gx[:, 0] - gy[:, 1]) + 1j * (gy[:, 0] + gx[:, 1])))
            want = _distortion(a, b, ~(signed_uv_areas(corner_uv) > 0))
            assert D.tobytes() == want.tobytes()
            assert np.array_equal(smin, (a - b).min(), equal_nan=True)
            assert np.array_equal(smax, (a + b).max(), equal_nan=True)
        if trial % 5 in (1, 2):
            assert np.isinf(D).any()
