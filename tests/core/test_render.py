"""bd_uv.render.uv_layout_png: pixel size, colours by distortion, failed faces left out."""
import subprocess
import sys

import numpy as np
import pytest
from matplotlib.image import imread

from bd_uv.colors import ABOVE_25, ABOVE_50, DEGENERATE, FLIPPED, GREY, RED
from bd_uv.render import uv_layout_png
from helpers import grid


def layout():
    """A flat grid's own coordinates as UVs: (corner_uv (m,3,2), m)."""
    V, F = grid(9, 8)
    return V[F][:, :, :2].copy(), len(F)


def pixels_near(img, rgba, tol=0.02):
    """How many pixels have (nearly) this colour."""
    return int(np.sum(np.all(np.abs(img[:, :, :3] - np.asarray(rgba)[:3]) < tol, axis=2)))


@pytest.mark.parametrize("size", [200, 517, 1024])
def test_png_has_the_requested_pixel_size(tmp_path, size):
    uv, m = layout()
    path = tmp_path / "a.png"
    uv_layout_png(path, uv, np.full(m, 1.5), 3.0, "caption\nsecond line", size_px=size)
    assert imread(path).shape == (size, size, 4)


def test_default_size_is_1024(tmp_path):
    uv, m = layout()
    assert uv_layout_png(tmp_path / "a.png", uv, np.ones(m), 2.0, "x") == str(tmp_path / "a.png")
    assert imread(tmp_path / "a.png").shape == (1024, 1024, 4)


def test_faces_take_the_distortion_colour(tmp_path):
    """All faces at D = 1 paint the layout grey; at D = C red (Lipman 2012, section 6.1)."""
    uv, m = layout()
    uv_layout_png(tmp_path / "grey.png", uv, np.ones(m), 4.0, "", size_px=400)
    uv_layout_png(tmp_path / "red.png", uv, np.full(m, 4.0), 4.0, "", size_px=400)
    grey, red = imread(tmp_path / "grey.png"), imread(tmp_path / "red.png")
    # The layout covers a large part of the picture; the colour bar holds both colours a little.
    assert pixels_near(grey, GREY) > 0.2 * 400 * 400 > 20 * pixels_near(grey, RED)
    assert pixels_near(red, RED) > 0.2 * 400 * 400 > 20 * pixels_near(red, GREY)


def test_faces_with_nan_uvs_are_not_drawn(tmp_path):
    """Faces of failed islands (NaN UVs) are skipped; the others keep their colours."""
    uv, m = layout()
    D = np.ones(m)
    D[: m // 2] = 60.0                      # blue (> 50)
    uv_layout_png(tmp_path / "all.png", uv, D, 3.0, "", size_px=400)
    uv[: m // 2] = np.nan                   # those faces' island failed
    uv_layout_png(tmp_path / "some.png", uv, D, 3.0, "", size_px=400)
    full, some = imread(tmp_path / "all.png"), imread(tmp_path / "some.png")
    assert pixels_near(full, ABOVE_50) > 0.05 * 400 * 400
    assert pixels_near(some, ABOVE_50) == 0  # no blue face drawn: no "> 50" swatch either
    assert pixels_near(some, GREY) > pixels_near(full, GREY)   # the rest fills the view


def test_every_face_failed_still_gives_a_picture(tmp_path):
    uv, m = layout()
    uv_layout_png(tmp_path / "a.png", np.full_like(uv, np.nan), np.full(m, np.nan), None,
                  "nothing certified", size_px=300)
    assert imread(tmp_path / "a.png").shape == (300, 300, 4)


def test_flipped_faces_are_purple_and_bad_shapes_raise(tmp_path):
    uv, m = layout()
    D = np.ones(m)
    D[:10] = np.inf
    flipped = np.zeros(m, bool)
    flipped[:10] = True
    uv_layout_png(tmp_path / "flip.png", uv, D, 2.0, "", size_px=300, flipped=flipped)
    uv_layout_png(tmp_path / "degen.png", uv, D, 2.0, "", size_px=300)
    flip, degen = imread(tmp_path / "flip.png"), imread(tmp_path / "degen.png")
    # Legend patches hold a little of each colour; the ten faces hold much more.
    assert pixels_near(flip, FLIPPED) > 3 * pixels_near(degen, FLIPPED)
    assert pixels_near(degen, DEGENERATE) > 3 * pixels_near(flip, DEGENERATE)
    with pytest.raises(ValueError):
        uv_layout_png(tmp_path / "b.png", uv, D[:-1], 2.0, "")


def test_importing_bd_uv_does_not_load_matplotlib():
    code = ("import sys, bd_uv, bd_uv.render, bd_uv.batch; "
            "assert 'matplotlib' not in sys.modules and 'bpy' not in sys.modules")
    assert subprocess.run([sys.executable, "-c", code]).returncode == 0


def test_long_captions_are_wrapped_to_the_picture_width():
    from bd_uv.render import DPI, wrap_caption
    caption = ("nefertiti: BD-LSCM, 1/1 islands, 562 faces, max distortion 1.588 <= 5, "
               "mean 1.051, 0 flipped, 0.05 s")
    font = 1024 / 90.0  # the renderer's font size for a 1024 px picture
    lines = wrap_caption(caption, 1024, font).split("\n")
    assert len(lines) >= 2 and " ".join(lines) == caption
    assert max(len(l) for l in lines) < 95  # the length that was cut off before wrapping
    width_pt = max(len(l) for l in lines) * 0.75 * font
    assert width_pt <= 0.92 * 1024 / DPI * 72.0


def test_the_legend_shows_only_what_is_drawn(tmp_path):
    """A certified layout (every face within C) gets no swatch for "> 25", "> 50", flipped or
    degenerate faces: none of those colours appears anywhere in the picture; one flipped face
    brings its swatch (and only its own)."""
    uv, m = layout()
    D = np.linspace(1.0, 2.5, m)
    uv_layout_png(tmp_path / "ok.png", uv, D, 2.5, "certified", size_px=400)
    ok = imread(tmp_path / "ok.png")
    for colour in (ABOVE_25, ABOVE_50, FLIPPED, DEGENERATE):
        assert pixels_near(ok, colour) == 0
    flipped = np.zeros(m, dtype=bool)
    flipped[0] = True
    uv_layout_png(tmp_path / "flip.png", uv, np.where(flipped, np.inf, D), 2.5, "", size_px=400,
                  flipped=flipped)
    flip = imread(tmp_path / "flip.png")
    assert pixels_near(flip, FLIPPED) > 0
    for colour in (ABOVE_25, ABOVE_50, DEGENERATE):
        assert pixels_near(flip, colour) == 0


def test_the_caption_sits_under_the_layout(tmp_path):
    """No blank band: what the equal aspect leaves unused is split above the layout and below the
    caption, not left as a band at the bottom."""
    uv, m = layout()
    uv = uv / uv.reshape(-1, 2).max(axis=0)          # the grid fills the unit square
    uv_layout_png(tmp_path / "a.png", uv, np.ones(m), 3.0, "one line of caption", size_px=500)
    img = imread(tmp_path / "a.png")
    inked = np.flatnonzero((img[:, :, :3] < 0.9).any(axis=(1, 2)))
    top_margin, bottom_margin = inked.min(), 500 - 1 - inked.max()
    assert bottom_margin < 0.07 * 500 and abs(top_margin - bottom_margin) < 0.03 * 500
