"""Before/after pictures for the README sections on section 5 and 6 of Lipman 2012.

    python3.11 scripts/paper_figures.py docs/images

Writes deform-annulus.png, deform-biharmonic.png, boundary-l-shape.png, stretch-corner.png and
improve-star.png; each shows two panels coloured by conformal distortion (Lipman's colours:
grey 1 to red at the bound, purple flipped). Needs matplotlib and triangle (dev requirements).
"""
import os
import sys

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.dirname(HERE))
sys.path.insert(0, os.path.join(os.path.dirname(HERE), "tests", "core"))

import bd_uv  # noqa: E402
from bd_uv.boundary import boundary_targets, fixed_boundary_map, oriented_loop  # noqa: E402
from bd_uv.colors import distortion_colors  # noqa: E402
from bd_uv.energies import energy, jacobian_operators  # noqa: E402
from bd_uv.frames import _solve_fixed  # noqa: E402
from bd_uv.geometry import local_coordinates  # noqa: E402
from bd_uv.improve import equilateral_distortion, improve  # noqa: E402
from planar import boundary_edges, circle, mesh_polygon, square, svd_of_maps  # noqa: E402


def panels(path, items, bound, title):
    """items: list of (X (n,2), F, D (m,), caption)."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.collections import PolyCollection
    from matplotlib.figure import Figure
    fig = Figure(figsize=(5 * len(items), 5.6), dpi=100)
    FigureCanvasAgg(fig)
    fig.suptitle(title, fontsize=11)
    for k, (X, F, D, cap) in enumerate(items):
        ax = fig.add_subplot(1, len(items), k + 1)
        ax.set_aspect("equal")
        ax.axis("off")
        flipped = np.linalg.det(np.stack([X[F[:, 1]] - X[F[:, 0]], X[F[:, 2]] - X[F[:, 0]]],
                                         2)) <= 0
        col = distortion_colors(D, bound, flipped=flipped)
        ax.add_collection(PolyCollection(X[F], facecolors=col, edgecolors=(0, 0, 0, 0.35),
                                         linewidths=0.3))
        lo, hi = X.min(0), X.max(0)
        pad = 0.03 * (hi - lo).max()
        ax.set_xlim(lo[0] - pad, hi[0] + pad)
        ax.set_ylim(lo[1] - pad, hi[1] + pad)
        ax.set_title(cap, fontsize=9)
    fig.savefig(path)
    print("wrote", path)


def distortion(X0, X1, F):
    s, det = svd_of_maps(X0, X1, F)
    D = s[:, 0] / s[:, 1]
    D[det <= 0] = np.inf
    return D


def plain(V2, F, H, P, method):
    ops = jacobian_operators(local_coordinates(np.column_stack([V2, 0 * V2[:, 0]]), F), F,
                             len(V2))
    Q, _, _ = energy(method, ops, np.ones(len(F)))
    u = _solve_fixed(Q, len(V2), H, P[:, 0] + 1j * P[:, 1])
    return np.column_stack([u.real, u.imag])


def caption(name, X0, X1, F, extra=""):
    D = distortion(X0, X1, F)
    nf = int(np.sum(~np.isfinite(D)))
    mx = np.max(D[np.isfinite(D)])
    return f"{name}: {nf} flipped, max distortion {mx:.2f}{extra}"


def fig_deform(out):
    V, F = mesh_polygon(square(6), [circle(16, 0.3)[::-1]], [[0.0, 0.0]], area=0.006)
    b = np.unique(boundary_edges(F))
    inner = b[np.linalg.norm(V[b], axis=1) < 0.5]
    outer = np.setdiff1d(b, inner)
    t = np.deg2rad(45)
    R = np.array([[np.cos(t), -np.sin(t)], [np.sin(t), np.cos(t)]])
    H = np.concatenate([outer, inner])
    P = np.concatenate([V[outer], V[inner] @ R.T + [0.3, 0.15]])
    X = plain(V, F, H, P, "dirichlet")
    res = bd_uv.deform(V, F, H, P, method="arap", bound=5.0)
    panels(os.path.join(out, "deform-annulus.png"),
           [(X, F, distortion(V, X, F), caption("harmonic", V, X, F)),
            (res.uv, F, res.distortion, caption("BD-ARAP, C = 5", V, res.uv, F))], 5.0,
           "Hole moved by (0.3, 0.15) and turned 45 degrees, outer square fixed")


def fig_biharmonic(out):
    V, F = mesh_polygon(square(8), area=0.01)
    b = np.unique(boundary_edges(F))
    c = int(np.argmin(np.linalg.norm(V - [-0.3, 0.0], axis=1)))
    H = np.concatenate([b, [c]])
    P = np.concatenate([V[b], V[[c]] + [0.9, 0.0]])
    X = plain(V, F, H, P, "biharmonic")
    res = bd_uv.deform(V, F, H, P, method="biharmonic", bound=5.0)
    panels(os.path.join(out, "deform-biharmonic.png"),
           [(X, F, distortion(V, X, F), caption("biharmonic", V, X, F)),
            (res.uv, F, res.distortion, caption("BD-Biharmonic, C = 5", V, res.uv, F))], 5.0,
           "Square, boundary fixed, one interior vertex moved right by 0.9 (paper's Figure 4)")


def fig_boundary(out):
    holes = [circle(12, 0.3, (0.2, 0.1))[::-1], circle(10, 0.2, (-0.5, -0.4))[::-1]]
    V2, F = mesh_polygon(square(8), holes, [[0.2, 0.1], [-0.5, -0.4]], area=0.008)
    V = np.column_stack([V2, 0.3 * np.exp(-2 * (V2 ** 2).sum(1))])
    isl = bd_uv.islands(V, F)[0]
    Vi = V[isl.vertices]
    lengths = [np.linalg.norm(Vi[np.roll(lp, -1)] - Vi[lp], axis=1).sum() for lp in isl.loops]
    outer = oriented_loop(isl.tris, isl.loops[int(np.argmax(lengths))])
    Pb = V2[isl.vertices[outer]]
    at = [int(np.argmin(np.linalg.norm(Pb - c, axis=1)))
          for c in [[-1, -1], [1, -1], [1, 1], [0, 1], [-1, 1], [-1, 0]]]
    Lp = np.array([[0, 0], [2, 0], [2, 1], [1, 1], [1, 2], [0, 2]], float)
    idx, uv = boundary_targets(Vi, isl.tris, isl.loops, "pinned", (outer[at], Lp))
    ops = jacobian_operators(local_coordinates(Vi, isl.tris), isl.tris, len(Vi))
    Q, _, _ = energy("dirichlet", ops, np.ones(len(isl.tris)))
    u = _solve_fixed(Q, len(Vi), idx, uv[:, 0] + 1j * uv[:, 1])
    X = np.column_stack([u.real, u.imag])
    res = fixed_boundary_map(Vi, isl.tris, isl.loops, idx, uv, bound=5.0)
    Dh = bd_uv.conformal_distortion(Vi, isl.tris, X[isl.tris])
    panels(os.path.join(out, "boundary-l-shape.png"),
           [(X, isl.tris, Dh, f"harmonic: {int(np.sum(~np.isfinite(Dh)))} flipped"),
            (res.uv, isl.tris, bd_uv.conformal_distortion(Vi, isl.tris, res.uv[isl.tris]),
             f"BD-Dirichlet, C = 5: 0 flipped, max {res.max_distortion:.2f}, "
             f"bijective: {res.premises.bijective}")], 5.0,
           "A bumpy square with two holes, outer boundary pinned onto an L (holes free)")


def fig_stretch(out):
    V, F = mesh_polygon(square(8), area=0.01)
    H = [int(np.argmin(np.linalg.norm(V - p, axis=1))) for p in [[-1, -1], [1, -1], [1, 1],
                                                                 [-1, 1]]]
    P = np.array([[-1, -1], [1, -1], [0.2, 0.2], [-1, 1]], float)
    a = bd_uv.deform(V, F, H, P, method="arap", bound=4.0)
    b = bd_uv.deform(V, F, H, P, method="arap", bound=4.0, stretch=2.0)

    def cap(name, X):
        s, _ = svd_of_maps(V, X, F)
        return f"{name}: singular values {s[:, 1].min():.3f} .. {s[:, 0].max():.3f}"
    panels(os.path.join(out, "stretch-corner.png"),
           [(a.uv, F, a.distortion, cap("BD-ARAP, C = 4", a.uv)),
            (b.uv, F, b.distortion, cap("with --stretch 2", b.uv))], 4.0,
           "Corner (1, 1) pulled to (0.2, 0.2): stretch bounds keep faces from collapsing")


def fig_improve(out):
    star = np.array([[np.cos(t) * (1 if k % 2 == 0 else 0.45),
                      np.sin(t) * (1 if k % 2 == 0 else 0.45)]
                     for k, t in enumerate(np.linspace(0, 2 * np.pi, 10, endpoint=False))])
    V, F = mesh_polygon(star, area=0.01)
    res = improve(V, F)
    D0, D1 = equilateral_distortion(V, F), res.distortion_after
    panels(os.path.join(out, "improve-star.png"),
           [(V, F, D0, f"Triangle (q30 a0.01): max {D0.max():.2f}"),
            (res.V2, F, D1, f"improved: max {D1.max():.2f}, boundary unchanged")],
           max(D0.max(), 2.0), "Distortion against the equilateral triangle")


if __name__ == "__main__":
    out = sys.argv[1] if len(sys.argv) > 1 else "docs/images"
    os.makedirs(out, exist_ok=True)
    for f in (fig_deform, fig_biharmonic, fig_boundary, fig_stretch, fig_improve):
        f(out)
