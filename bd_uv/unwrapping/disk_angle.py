"""``bound="auto"`` from a clean disk's angle start, on its ``one_disk.Disk`` geometry (issue 21
item 2: no set-up made twice).

Where ``angle_start.better_start`` takes a disk's angle start (its conformal start flips, lies over
itself or is far from conformal), the general path (``island_solve.solve_island``) made an
``IslandProblem`` of the disk (its vertices centred and scaled, their local frames, the four
sparse Jacobian operators), measured the start there, searched its least map that does not lie
over itself (``strategies.minimise`` with ``one_to_one``: ``least_one_to_one``), relaxed its
mean (``mean_relax``; ``energy_within.weighted_lowered`` where it stays over the angle
start's), placed and certified it (``finish``), and certified the disk's UVs again
(``one_disk.certify``). Every piece of that the search needs is in the ``Disk`` already: each
face's gradient operator and area (the conformal maps were solved from them) and the vertices'
elimination order. Here the same steps run on them: the bound search (``searched.search``'s,
the same targets, stops and tests: each target's best recorded, every tested map's boundary
loop checked, the least that lays the disk out kept), the relaxation, and the disk certificate
of the map as ``finish`` places it (``disk_auto``'s). The search's iterations do not depend on
the geometry's scale or place, so the maps are the general path's up to rounding (its copy is
normalised to unit area): on the 7 angle-start disks of issue 21's table, the same iterations,
C and flags, the means equal to 1e-13 (``benchmarks/results/issue21-auto31-2026-11-29.md``).

Anything else goes the general way, which decides as before: no flip-free start, a start or a
map it cannot certify at once (over ``finish.HIGH_DISTORTION``, a stored map over its search's
bound, a boundary the disk certificate does not clear), a time budget (its conic steps).
"""
import time

import numpy as np

from ..array_calls import einsum
from ..certificate import RTOL
from ..energies import JacobianOperators
from ..errors import CancelledError
from ..solvers import bound_search
from .disk_auto import _certified
from .disk_certificate import simple_ccw_loop, turns_once
from .finish import certified_bound
from .mean_relax import face_distortion, relaxed
from . import energy_within
from .energy_within import weighted_lowered
from .one_disk import report_step
from .results import IslandResult, UnwrapResult
from .searched import FREE_FACES, drop_handed
from . import strategies

__all__ = ["minimise_from_angles"]


def minimise_from_angles(V, disk, v, limit, t0, progress=None, cancel=None):
    """The least certified C of a ``Disk`` from its angle start v (nv,) complex128
    (``angle_start.better_start``'s), among the search's maps that lay the disk out without
    overlapping itself, as ``strategies.minimise`` finds it with ``one_to_one`` and no time
    budget (``limit``: ``bound_limit``).

    Returns
    -------
    UnwrapResult (flags "angle_start", "mean_relaxed", "mean_lowered", "projected" or
    "initial_map", as the general path's), or None where the general path must decide (see
    the module's docstring)

    Raises
    ------
    CancelledError when ``cancel`` is set
    """
    isl = disk.island
    tris, loop = isl.tris, isl.loops[0]
    k, nv = len(tris), len(isl.vertices)
    G = disk.G
    cb = 0.5 * (G[:, 0] + 1j * G[:, 1])         # (``lscm.face_geometry_of``'s)

    def distortion(u):
        return float(np.maximum.reduce(face_distortion(cb, tris, u)))

    def lays_out(u):        # ``IslandProblem.lays_out`` of a disk: its boundary loop's test
        return turns_once(u.take(loop)) and bool(simple_ccw_loop(
            np.stack([u.real, u.imag], axis=1).take(loop, axis=0)))
    # (the general path's search from v would forget a search handed over from the conformal
    # start: ``disk_auto``'s, which a conformal start's search after this one must not take)
    drop_handed()
    D0 = distortion(v)
    if not np.isfinite(D0):
        return None
    t = time.perf_counter()
    # ``searched.search`` with ``least``: one boundary vertex held where v has it, the disk's
    # vertex order, the free unknowns up to FREE_FACES faces, the effort bounded
    ops = JacobianOperators(None, None, None, None, disk.area, tris, G[:, 0, :], G[:, 1, :])
    bs = bound_search.BoundSearch(ops, nv, tris, loop[:1], connected=True, ranks=disk.ranks,
                                  free=True if k <= FREE_FACES else None)
    bs.limit_effort()
    # ``strategies.least_one_to_one``: each target's best kept at its end, a folded one ending
    # the search; every tested map kept with its test, the search ended at one lying over itself
    # (each with its max distortion, its test where made, and whether that max is ``distortion``'s
    # or the search's own)
    kept = [(v, D0, None, True)]

    def record(u):
        if not np.array_equal(kept[-1][0], u):
            kept.append((u, distortion(u), None, True))
        return strategies.FOLDED_ENDS and not turns_once(u.take(loop))

    def check(u):
        laid = lays_out(u)
        kept.append((u, distortion(u), laid, True))
        return not laid
    bs.check = check if strategies.OVERLAP_ENDS else None     # (the gates read at the call)

    def report(D, C):
        report_step(progress, cancel, 0.1, f"island 1/1: minimising C: C* <= {D:.4g}, aiming at "
                    f"{C:.4g}")
    us, D, _ = bs.search(v, None, report, None, cancel, record,
                         _always if strategies.FOLDED_ENDS else None)
    if cancel is not None and cancel.is_set():
        raise CancelledError("unwrap cancelled; nothing was changed")
    if np.array_equal(kept[-1][0], us):
        kept[-1] = (us, D, kept[-1][2], False)
    else:
        kept.append((us, D, None, False))
    u, laid_u, own = us, None, False
    for w, Dw, laid, mine in sorted(kept, key=lambda c: c[1]):
        if np.isfinite(Dw) and (laid if laid is not None else lays_out(w)):
            u, D, laid_u, own = w, Dw, True, mine
            break
    # ``strategies.minimise``'s choice and relaxation, measured in this geometry (a max that
    # ``distortion`` measured is not measured again, nor the test of a map that passed it)
    best = (v, D0) if D0 <= limit else None
    if bs.iterations == 0 and best is not None:
        u, D, laid_u, own = v, D0, None, True
    flags = ["angle_start"]
    if (D < best[1]) if best is not None else (D <= limit):
        Du = D if own else distortion(u)
        if Du <= D * (1 + 1e-9) or (Du <= limit and (best is None or Du < best[1])):
            best = (u, Du)
            y = relaxed(disk.Z, G, disk.area, tris, nv, v, u, ranks=disk.ranks)
            if y is not None:
                Dy = distortion(y)
                if Dy <= Du and (lays_out(y) or not (
                        laid_u if laid_u is not None else lays_out(u))):
                    best = (y, Dy)
                    flags.append("mean_relaxed")
            laid = (lays_out(best[0]) if best[0] is not u or laid_u is None else laid_u)
            low = (_lowered(disk, ops, cb, v, best[0], best[1], lays_out)
                   if energy_within.LOWER and laid else None)
            if low is not None:
                best = low
                flags.append("mean_lowered")
    project = time.perf_counter() - t
    if best is None:
        return None
    flags.append("initial_map" if best[0] is v else "projected")
    t = time.perf_counter()
    # ``finish``'s placement and test, then the disk certificate of the UVs as placed
    done = _certified(best[0], disk, float(np.add.reduce(disk.area)), "auto",
                      certified_bound(best[1]) * (1.0 + RTOL))
    if done is None:
        return None
    uv, Dm, C, mean, smin, smax, cert = done
    mx = float(Dm.max())
    res = IslandResult(
        0, isl.faces, isl.vertices, tris, uv=uv, status="certified",
        message=f"island 0: {k} faces, max distortion {mx:.3f} <= {C:.4g}, 0 flipped",
        bound_requested="auto", bound_certified=float(C), max_distortion=mx,
        mean_distortion=mean, flipped=0, frames="conformal",
        seconds=time.perf_counter() - t0, iterations=bs.iterations, distortion=Dm,
        flags=tuple(flags), overlap_free=True, min_singular=smin, max_singular=smax,
        timings={"setup": 0.0, "solve": 0.0, "certify": time.perf_counter() - t,
                 "project": project})
    report_step(progress, cancel, 1.0, "island 1/1: minimised")
    if progress is not None:
        progress(1.0, "done")
    return UnwrapResult(uv.take(tris, axis=0), np.zeros(k, dtype=np.int64), [res],
                        time.perf_counter() - t0, "lscm", certificates=(cert,))


class _DiskProblem:
    """What ``energy_within.weighted_lowered`` reads of an ``IslandProblem``, on a ``Disk``'s
    geometry."""

    def __init__(self, disk, ops, cb):
        isl = disk.island
        self.ops, self.nv, self.Z, self.island, self.ranks = (ops, len(isl.vertices), disk.Z,
                                                               isl, disk.ranks)
        self.cb, self.tris = cb, isl.tris

    def alpha(self, u):
        return einsum("fc,fc->f", self.cb.conj(), u.take(self.tris))

    def face_distortion(self, u):
        return face_distortion(self.cb, self.tris, u)


def _lowered(disk, ops, cb, v, u, D, lays_out):
    """``energy_within.weighted_lowered`` of the map u (max distortion D, laying the disk out)
    on the ``Disk``'s geometry, where its mean is over the angle start v's by more than
    ``energy_within.LOWER_RISE``: (map, its max) or None."""
    return weighted_lowered(_DiskProblem(disk, ops, cb), v, u, D, lays_out)


def _always(u):
    return True
