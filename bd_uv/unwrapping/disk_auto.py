"""``bound="auto"`` on a mesh that is one clean disk, from its ``one_disk.Disk`` geometry (issue 21
item 1: auto's own set-up on the smallest disks).

The general path (``island_solve.solve_island``, ``strategies.minimise``, ``finish``) builds an
``IslandProblem`` for the island (normalised coordinates, their local frames, the four sparse
Jacobian operators), measures the conformal map's distortion and frames there, searches, measures
the searched map again, and certifies it. For a small disk whose conformal map is flip-free
within the limit, every piece of that the search needs is already in the ``Disk``: each face's
gradient operator and area (the conformal map was solved from them), and the vertices' elimination
order. Here the bound search (``solvers.bound_search``, the general path's search, the same
targets and stops) runs on them, and the map is placed as ``finish`` places it and certified by
``disk_certificate`` at the bound ``finish`` reports. The search's iterations do not depend on
the geometry's scale or place, so the maps are the general path's up to rounding (the general
path works on a copy centred and scaled to unit area). Where the search raised the mean distortion
well over the conformal map's, its faces below the max are given back to the conformal map
(``mean_relax``, as the general path does): kept when that map certifies at a C no higher.

Anything else goes the general way: a conformal map that flips or exceeds the limit (bent into a
bound first), a time budget (Dinkelbach steps), more than AUTO_FACES faces for the least C (more
than ``bound_search.ONE_PRODUCT_FACES`` for a numeric C whose conformal map lies over itself), a
map the disk certificate does not clear. Over ``bound_search.ONE_PRODUCT_FACES`` faces (where the
general path searched before AUTO_FACES was raised) a conformal map whose boundary is not one
simple loop goes the general way at once: its search here would mostly end in a map the
certificate does not clear, and the general path would search again.
"""
import time

import numpy as np

from ..certificate import RTOL
from ..energies import JacobianOperators
from ..errors import CancelledError
from ..metrics import mean_distortion
from ..solvers import bound_search
from .disk_certificate import (certify_measured_disk, measure_disk, simple_ccw_loop,
                               turns_once)
from . import mean_relax, searched
from .finish import HIGH_DISTORTION, certified_bound, placed
from .one_disk import report_step
from .results import IslandResult, UnwrapResult

__all__ = ["minimise_disk", "searches"]

# ``bound="auto"`` on a clean disk of up to this many faces is searched here, on the free
# unknowns (``bound_search.BoundSearch``'s free path, whatever ``ONE_PRODUCT_FACES``). Was
# ONE_PRODUCT_FACES (1000): from 1,000 to 2,000 faces the general path's set-up (its island
# problem, the sparse operators, ``finish``, the general certificate) cost 1-3 ms more and its
# iterations on the whole map 10-25 % more an iteration than the free ones (spot's 1,046-face
# patch 1.8-2.0x -> 1.5-1.7x Blender ABF's CPU, libigl arm's 1,234-face patch 1.25-1.36x ->
# 1.07-1.10x, screwdriver's 1,846-face patch 1.33-1.36x -> 1.11-1.14x; the same iterations and
# C, the UVs to 3e-13: issue21-auto16). From ~2,000 faces the free iterations (twice the
# gradient products' entries) cost as much, and more from 2,500 (libigl max's 2,594-face patch
# +13 %, hemisphere.obj's 4,000 faces +10 % at load 10).
AUTO_FACES = 2000


def searches(disk, auto=False):
    """Does ``minimise_disk`` search this ``Disk`` (else it leaves it to the general path), for
    a numeric C whose conformal map lies over itself (``unwrap``'s question), or for the least C
    (``auto``)?"""
    # the gates are read at the call (tests set them)
    return len(disk.island.tris) <= (AUTO_FACES if auto else bound_search.ONE_PRODUCT_FACES)


def minimise_disk(V, disk, u, limit, t0, progress=None, cancel=None, requested="auto"):
    """The smallest certified C of a ``Disk`` from its conformal map u (nv,) complex128
    (``one_disk.unwrap_disk``'s), as ``strategies.minimise`` finds it without a time budget.

    ``requested``: the bound asked for, "auto", or a number C (= ``limit``) whose conformal map
    lay over itself: the search for the smallest C runs (aiming deeper:
    ``bound_search.UNFOLD_MARGIN``) until an iterate that is the least yet no longer does (asked
    as soon as its boundary turns once, ``disk_certificate.turns_once``, and certified then), so
    that the disk stays one island (a map of lower distortion moves the boundary:
    on three_peaks' 554-face centre the conformal map at C = 5 folded over and was cut into 3
    islands, one of a single face, where the search's maps are one); flagged "unfolded",
    certified at the C asked (its max distortion says how far below it the map is).

    Returns
    -------
    UnwrapResult, or None where the general path must decide (see the module's docstring)

    Raises
    ------
    CancelledError when ``cancel`` is set
    """
    isl = disk.island
    k, nv = len(isl.tris), len(isl.vertices)
    unfold = requested != "auto"
    if not searches(disk, not unfold):
        return None
    if k > bound_search.ONE_PRODUCT_FACES and not simple_ccw_loop(
            np.array([u.real, u.imag]).T.take(isl.loops[0], axis=0)):
        return None     # lying over itself: the general path (see the module's docstring)
    t = time.perf_counter()
    area3d = float(np.add.reduce(disk.area))
    # the disk's own geometry (the conformal map's gradient operators and areas): the
    # iterations do not depend on its scale or place, so the maps are those of the general
    # path's copy normalised to unit area (``problem.normalised``) up to rounding, the same C
    # (its frames and operators made again cost ~50 us of a 115-face disk's ~1.2 ms)
    Gn, An = disk.G, disk.area
    ops = JacobianOperators(None, None, None, None, An, isl.tris, Gn[:, 0, :], Gn[:, 1, :])
    bs = bound_search.BoundSearch(ops, nv, isl.tris, isl.loops[0][:1], connected=True,
                                  ranks=disk.ranks, free=True)
    D0 = bs.distortion_of(u)
    if not (np.isfinite(D0) and D0 <= limit):
        return None
    if not unfold:      # the least C: the general path's bounds (``strategies.minimise``)
        bs.limit_effort()

    def report(D, C):
        report_step(progress, cancel, 0.1, f"island 1/1: minimising C: C* <= {D:.4g}, aiming at "
                f"{C:.4g}")
    loop = isl.loops[0]
    found = []

    def one_to_one(v):
        """The map placed and certified by the disk certificate (kept in ``found``)?"""
        done = _certified(v, disk, area3d, requested, limit)
        if done is not None:
            found.append(done)
        return done is not None

    def turns_once_(v):     # asked of every iterate that is the least yet: refuses cheaply
        return turns_once(v.take(loop))
    # a number whose conformal map lay over itself: the first map of the search that does not
    # is enough (the user asked for C, not the least C; nearer the conformal map)
    us, D, _ = bs.search(u, None, report, None, cancel, *((one_to_one, turns_once_) if unfold
                                                           else (None, None)), deep=unfold)
    if cancel is not None and cancel.is_set():
        raise CancelledError("unwrap cancelled; nothing was changed")
    project = time.perf_counter() - t
    flags = (("projected",) if D < D0 else ("initial_map",)) + (
        ("unfolded",) if unfold else ())
    if D >= D0 and not found:
        us, D = u, D0
    t = time.perf_counter()
    # finish's test (the map within the bound its search reached) and the disk certificate, at
    # the C asked when it was a number (the map found is within it, with room for float32)
    done = (found[-1] if found else
            _certified(us, disk, area3d, requested, certified_bound(D) * (1.0 + RTOL)))
    if done is None:
        if not unfold and D < D0:   # the general path's search from u: this one's map
            searched.hand_over(isl, u, us, D, bs.iterations)
        return None
    relax = 0.0
    if not unfold and D < D0:
        # the search's min-max map, its faces below the max given back to the conformal map
        # where the search raised the mean (``mean_relax``): kept when it certifies at a C no
        # higher and its mean is lower
        t1 = time.perf_counter()
        y = mean_relax.relaxed(disk.Z, disk.G, disk.area, isl.tris, nv, u, us,
                               (disk.twins[0], disk.twins[1], disk.loop), disk.ranks,
                               mean=done[3])
        relax = time.perf_counter() - t1
        better = None if y is None else _certified(y, disk, area3d, requested, np.inf, done[2])
        if better is not None and better[3] < done[3]:
            done, flags, us = better, flags + ("mean_relaxed",), y
        # a mean still far over the conformal map's: C given back for it (``mean_relax.capped``;
        # a mean within its cap is refused there unmeasured, asked here before any array op)
        y = (mean_relax.capped(0.5 * (disk.G[:, 0] + 1j * disk.G[:, 1]), disk.area, isl.tris,
                               u, us, done[3])
             if done[3] > (1.0 + mean_relax.MEAN_CAP) * (1.0 - 1e-9) else None)
        better = None if y is None else _certified(y, disk, area3d, requested, D0)
        if better is not None and better[1].max() < D0:
            done, flags = better, flags + ("mean_capped",)
    uv, Dm, C, mean, smin, smax, cert = done
    mx = float(Dm.max())
    res = IslandResult(
        0, isl.faces, isl.vertices, isl.tris, uv=uv, status="certified",
        message=f"island 0: {k} faces, max distortion {mx:.3f} <= {C:.4g}, 0 flipped",
        bound_requested=requested, bound_certified=float(C), max_distortion=mx,
        mean_distortion=mean, flipped=0, frames="conformal",
        seconds=time.perf_counter() - t0, iterations=bs.iterations, distortion=Dm, flags=flags,
        overlap_free=True, min_singular=smin, max_singular=smax,
        timings={"setup": 0.0, "solve": 0.0, "certify": time.perf_counter() - t - relax,
                 "project": project + relax})
    report_step(progress, cancel, 1.0, "island 1/1: minimised")
    if progress is not None:
        progress(1.0, "done")
    return UnwrapResult(uv.take(isl.tris, axis=0), np.zeros(k, dtype=np.int64), [res],
                        time.perf_counter() - t0, "lscm", certificates=(cert,))


def _certified(u, disk, area3d, requested, bound, most=HIGH_DISTORTION):
    """The map u (nv,) complex placed as ``finish`` places a map of no pin, measured and
    certified by the disk certificate, when its max distortion is within ``bound`` and the C
    ``bound="auto"`` reports for it (``certified_bound``) within ``most`` (and HIGH_DISTORTION).

    Returns (uv (nv,2), each face's distortion, the certified C, the area-weighted mean
    distortion, min and max singular values, the certificate), or None."""
    isl = disk.island
    us = placed(u, isl.tris, area3d)
    uv = np.empty((len(us), 2))            # np.stack(..., axis=1) without its wrapper
    uv[:, 0], uv[:, 1] = us.real, us.imag
    corner_uv = uv.take(isl.tris, axis=0)
    Dm, smin, smax = measure_disk(corner_uv, disk.G)
    mx = float(Dm.max())
    C = certified_bound(mx)
    if not (mx <= bound and C <= min(most, HIGH_DISTORTION)):
        return None
    C = C if requested == "auto" else max(C, float(requested))
    cert = certify_measured_disk(corner_uv, Dm, disk, C)
    if cert is None:
        return None
    return uv, Dm, C, mean_distortion(None, None, Dm, disk.area), smin, smax, cert

