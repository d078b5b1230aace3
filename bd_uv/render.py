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

    font = max(6.0, size_px / 90.0)
    caption = wrap_caption(caption, size_px, font) if caption else ""
    # Figure(), not pyplot: no global state, safe in worker processes and threads.
    fig = Figure(figsize=(size_px / DPI, size_px / DPI), dpi=DPI)
    FigureCanvasAgg(fig)
    # The caption takes the lines it needs at the bottom; the layout takes the rest (no blank band).
    line = 1.3 * font / 72.0 * DPI / size_px           # one caption line, in figure fractions
    text_h = (caption.count("\n") + 1) * line if caption else 0.0
    bottom = 0.02 + text_h + 0.065                      # caption, then the u axis and its label
    ax = fig.add_axes((0.07, bottom, 0.79, 0.975 - bottom))
    ax.set_aspect("equal")
    ax.set_anchor("N")
    ax.tick_params(labelsize=font * 0.8)
    ax.set_xlabel("u", fontsize=font)
    ax.set_ylabel("v", fontsize=font, rotation=0, labelpad=font)
    if drawn.any():
        # Edges a shade darker than their face, opaque: thin translucent edges drawn twice (once
        # per face) alias into dashes when zoomed.
        face = colors[drawn]
        edge = np.concatenate([face[:, :3] * 0.8, face[:, 3:]], axis=1)
        polys = PolyCollection(corner_uv[drawn], facecolors=face, edgecolors=edge,
                               linewidths=0.15 if drawn.sum() > 2000 else 0.35)
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

    # The layout's box as drawn (equal aspect, anchored at the top): the colour bar beside it and
    # the caption right under it.
    ax.apply_aspect()
    box = ax.get_position()
    spare = box.y0 - bottom                             # what the equal aspect left unused
    if spare > 0:                                       # split it above and below, not all below
        ax.set_position((box.x0, box.y0 - spare / 2, box.width, box.height))
        box = ax.get_position()
    cax = fig.add_axes((0.885, box.y0 + 0.35 * box.height, 0.03, 0.65 * box.height))
    # Colour bar: the grey-to-red ramp over [1, C], sampled from the same colour function, its
    # top tick the bound itself.
    ramp = distortion_colors(np.linspace(1.0, C, 256), C)
    mappable = ScalarMappable(norm=Normalize(1.0, C), cmap=ListedColormap(ramp))
    bar = fig.colorbar(mappable, cax=cax)
    ticks = [t for t in bar.get_ticks() if 1.0 <= t < C - 0.04 * (C - 1.0)] + [C]
    bar.set_ticks(ticks)
    bar.set_ticklabels([f"{t:g}" for t in ticks[:-1]] + [f"C = {C:.4g}"])
    bar.set_label("conformal distortion", fontsize=font)
    bar.ax.tick_params(labelsize=font * 0.8)
    # Only what the picture shows gets a swatch: a certified layout has none of these.
    finite = np.isfinite(distortion)
    shown = drawn if flipped is None else drawn & ~np.asarray(flipped, dtype=bool)
    kinds = [(ABOVE_25, "> 25", shown & finite & (distortion > 25.0) & (distortion <= 50.0)),
             (ABOVE_50, "> 50", shown & finite & (distortion > 50.0)),
             (FLIPPED, "flipped", drawn & (np.asarray(flipped, dtype=bool) if flipped is not None
                                           else False)),
             (DEGENERATE, "degenerate", shown & ~finite)]
    legend = [Patch(color=c, label=label) for c, label, mask in kinds if np.any(mask)]
    if legend:
        fig.legend(handles=legend, loc="upper left", frameon=False, fontsize=font * 0.85,
                   bbox_to_anchor=(0.865, box.y0 + 0.33 * box.height))
    if caption:
        fig.text(0.04, box.y0 - 0.065, caption, ha="left", va="top", fontsize=font,
                 family="monospace")
    fig.savefig(path, dpi=DPI, format="png")
    return str(path)
