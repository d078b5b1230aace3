"""Picture of a UV layout for sign-off: faces coloured by distortion, a colour bar, the figures.

The colours are Lipman 2012's scheme (section 6.1, ``bd_uv.colors.distortion_colors``): grey at
distortion 1 ramping to red at the bound C, green above 25, blue above 50, purple for flipped and
yellow for degenerate faces. Drawing uses matplotlib's Agg canvas (a ``PolyCollection`` per call),
imported inside the function so that ``import bd_uv`` stays light and Blender never loads it unless
a picture is asked for.
"""
import numpy as np

from .colors import ABOVE_25, ABOVE_50, DEGENERATE, FLIPPED, distortion_colors

DPI = 100


def _ramp_bound(distortion, bound):
    """The C used for the colour ramp: ``bound`` when usable, else the largest finite distortion."""
    try:
        C = float(bound)
    except (TypeError, ValueError):
        C = float("nan")
    if np.isfinite(C) and C > 1.0:
        return C
    finite = distortion[np.isfinite(distortion)]
    top = float(finite.max()) if finite.size else 2.0
    return top if top > 1.0 + 1e-6 else 2.0


def wrap_caption(caption, size_px, font):
    """The caption broken into lines that fit 92 % of the picture's width. A monospace glyph is
    taken as 0.75 em: measured, a 1024 px picture cut an unwrapped caption at about 95 characters,
    where 0.6 em would promise 108."""
    import textwrap
    width_pt = 0.92 * size_px / DPI * 72.0
    per_line = max(20, int(width_pt / (0.75 * font)))
    return "\n".join(textwrap.fill(part, per_line) for part in caption.split("\n"))


def uv_layout_png(path, corner_uv, distortion, bound, caption, size_px=1024, flipped=None,
                  tiles=(), padding=0.0):
    """Write a ``size_px`` x ``size_px`` PNG of a UV layout coloured by conformal distortion.

    Parameters
    ----------
    path : str or os.PathLike
        Where to write the PNG (parent folder must exist).
    corner_uv : (m,3,2) float array
        UV of each face corner. Faces with any NaN UV (their island failed) are not drawn.
    distortion : (m,) float array
        Conformal distortion per face (``inf`` for flipped or degenerate faces).
    bound : float or None
        The certified bound C; the grey-to-red ramp reaches red there. ``None`` (nothing certified)
        ramps up to the largest finite distortion instead.
    caption : str
        Text printed under the layout (object name, C, max/mean distortion, flips, ...); newlines
        start new lines.
    size_px : int
        Width and height of the PNG in pixels.
    flipped : (m,) bool array, optional
        Faces known to be flipped, drawn purple (otherwise non-finite faces are drawn yellow).
    tiles : sequence of int, optional
        UDIM tiles of a packed layout (1001: the unit square): each is outlined, with a dashed
        line half the padding inside it.
    padding : float
        The packing's padding, in UV units.

    Returns
    -------
    path : str
        The path written.
    """
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.cm import ScalarMappable
    from matplotlib.collections import PolyCollection
    from matplotlib.colors import ListedColormap, Normalize
    from matplotlib.figure import Figure
    from matplotlib.patches import Patch, Rectangle

    corner_uv = np.asarray(corner_uv, dtype=np.float64).reshape(-1, 3, 2)
    distortion = np.asarray(distortion, dtype=np.float64).reshape(-1)
    if distortion.shape[0] != corner_uv.shape[0]:
        raise ValueError(f"distortion has {distortion.shape[0]} faces, corner_uv has "
                         f"{corner_uv.shape[0]}")
    size_px = int(size_px)
    if size_px < 64:
        raise ValueError(f"size_px must be at least 64, got {size_px}")
    C = _ramp_bound(distortion, bound)
    colors = distortion_colors(distortion, C, flipped=flipped)
    drawn = np.isfinite(corner_uv).all(axis=(1, 2))

    # Figure(), not pyplot: no global state, safe in worker processes and threads.
    fig = Figure(figsize=(size_px / DPI, size_px / DPI), dpi=DPI)
    FigureCanvasAgg(fig)
    font = max(6.0, size_px / 90.0)
    ax = fig.add_axes((0.04, 0.20, 0.80, 0.77))
    cax = fig.add_axes((0.87, 0.40, 0.03, 0.57))
    ax.set_aspect("equal")
    ax.tick_params(labelsize=font * 0.8)
    if drawn.any():
        polys = PolyCollection(corner_uv[drawn], facecolors=colors[drawn],
                               edgecolors=(0.0, 0.0, 0.0, 0.25),
                               linewidths=0.1 if drawn.sum() > 2000 else 0.3)
        ax.add_collection(polys)
        lo = corner_uv[drawn].reshape(-1, 2).min(axis=0)
        hi = corner_uv[drawn].reshape(-1, 2).max(axis=0)
        for t in tiles:
            u, v = (t - 1001) % 10, (t - 1001) // 10
            ax.add_patch(Rectangle((u, v), 1, 1, fill=False, linewidth=1.0, edgecolor="black"))
            h = 0.5 * padding
            ax.add_patch(Rectangle((u + h, v + h), 1 - padding, 1 - padding, fill=False,
                                   linewidth=0.6, linestyle="--", edgecolor="tab:blue"))
            lo, hi = np.minimum(lo, (u, v)), np.maximum(hi, (u + 1, v + 1))
        pad = 0.02 * max(float((hi - lo).max()), 1e-12)
        ax.set_xlim(lo[0] - pad, hi[0] + pad)
        ax.set_ylim(lo[1] - pad, hi[1] + pad)
    else:
        ax.text(0.5, 0.5, "no UVs: every island failed", ha="center", va="center",
                fontsize=font * 1.4, transform=ax.transAxes)
        ax.set_xticks([])
        ax.set_yticks([])

    # Colour bar: the grey-to-red ramp over [1, C], sampled from the same colour function.
    ramp = distortion_colors(np.linspace(1.0, C, 256), C)
    mappable = ScalarMappable(norm=Normalize(1.0, C), cmap=ListedColormap(ramp))
    bar = fig.colorbar(mappable, cax=cax)
    bar.set_label("conformal distortion", fontsize=font)
    bar.ax.tick_params(labelsize=font * 0.8)
    legend = [Patch(color=ABOVE_25, label="> 25"), Patch(color=ABOVE_50, label="> 50"),
              Patch(color=FLIPPED, label="flipped"), Patch(color=DEGENERATE, label="degenerate")]
    fig.legend(handles=legend, loc="upper left", bbox_to_anchor=(0.845, 0.37), frameon=False,
               fontsize=font * 0.85)

    fig.text(0.04, 0.16, wrap_caption(caption, size_px, font), ha="left", va="top",
             fontsize=font, family="monospace")
    fig.savefig(path, dpi=DPI, format="png")
    return str(path)
