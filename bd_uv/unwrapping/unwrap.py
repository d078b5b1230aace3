"""Certified bounded-distortion unwrapping of a whole mesh, island by island.

Per island (Lipman 2012, sections 4 and 6; issue 9's "never worse than its start"):
1. a start map (``initial.start_map``): the free-boundary conformal map when it has no flipped
   face, else a flip-free map; on one clean disk whose conformal map flips, lies over itself or
   is far from conformal, its angle start (``angle_start``, Linear ABF) where that is better;
2. a start within the bound is returned as it is; otherwise it is bent only where the bound demands
   (``bounded.bounded``), or C is minimised (``strategies.minimise``);
3. every result is certified from its final UVs: no flipped face and max distortion <= C.
With ``boundary`` other than "free", steps 1-2 are replaced by a solve with the island's outer
boundary fixed on a circle, a rectangle or its pinned polygon (``fixed_boundary``, section 5),
certified the same way and checked for Theorems 5.1/5.2's premises (``bijective``).
One island's solve is ``island_solve.solve_island``; here the mesh is checked and split, the
batched conformal maps and the one-disk pass run, and the islands are gathered and certified. A
disk ``bound="auto"`` left cut is tried again to keep it one island (``_kept_whole``); one whose
angle start is taken is searched on its own geometry first (``disk_angle``).
"""
import dataclasses
import functools
import time

import numpy as np

from ..errors import CancelledError, InvalidMeshError, OptionError
from ..mesh import as_indices, as_reals, check_arrays, checked_islands as split_islands
from ..options import unwrap_options
from ..solvers.ordered_ldl import AUTO_RANKED_VERTICES
from ..trim import keep_freed_heap, release_memory
from . import angle_start, capped, disk_angle, disk_auto, one_disk
from .batched import conformal_islands
from .island_solve import (angle_unfolder, batched_options, solve_island, unfold_first,
                           unfolder)
from .overlap_certificate import overlap_certificate
from .rounding import predicted_to_fail, tightened
from .conic_solves import Cancelled
from .results import UnwrapResult

def unwrap(V, F, seams=None, pin_corners=None, pin_uv=None, *, initial_uv=None,
           face_groups=None, progress=None, cancel=None, options=None, precision=None,
           disk=None, whole=True, **values):
    """Map a triangle mesh, cut along the given seams, to the plane with no flipped face and
    conformal distortion <= C.

    Parameters
    ----------
    V : (n,3) float array
    F : (m,3) int array
    seams : (s,2) int array, optional, vertex pairs of the edges to cut along (adding seams,
        ``seams_mode="auto"``/``seams="auto"``, is ``bd_uv.unwrap``'s: ``bd_uv.api``)
    pin_corners : (p,) int array, optional, flat corner indices (face * 3 + corner)
    pin_uv : (p,2) float array, optional, the UV of each pinned corner (kept exactly)
    initial_uv : (m,3,2) float array, optional, per-corner UVs (needed for frames="input-uv":
        they are the start map, returned as they are when within the bound)
    face_groups : (m,) int array, optional, a group per face (the polygon each triangle comes
        from): an overlap cut never separates faces of one group
    progress : callable(fraction, message), optional
    cancel : object with ``is_set()``, optional
    options : bd_uv.UnwrapOptions, optional (default: the defaults)
    precision : the float type ``V`` was stored in, optional (``np.float32``): faces it cannot
        tell from a line are zero-area, and refuse their island (``DegenerateFacesError``) as
        a zero-area face does (``mesh.thinner_than_precision``)
    disk : one_disk.Disk, optional, ``one_disk.find(V, F)`` where the caller has found it
        already (``seams.needed.clean_disk``): not found again; used only where ``find`` would
        be called
    whole : bool, with ``bound="auto"`` a disk left cut is tried again (``_kept_whole``);
        False inside those tries
    **values : UnwrapOptions fields replacing those of ``options`` (``bound=3.0``, ...). How each
        works: ``method`` "biharmonic" (eq. 6.1) with a free boundary is held at two boundary
        vertices of the start map; "stretch-l1" (section 6.1) holds the island's scale (the
        area-weighted mean of Re(w alpha) = 1 on the unit-area island, one anchor vertex;
        ``IslandProblem.hold_scale``) unless two or more pins or a fixed boundary give it.
        ``stretch`` is relative to the island's own scale (UV area = 3D area) with a free
        boundary and fewer than two pins, else to the 3D geometry, certified from the final UVs
        (``min_singular``, ``max_singular``); with bound="auto" the smallest C within S is
        sought. ``boundary`` other than "free" fixes the outer boundary on a circle or a
        rectangle of the island's 3D area (corners at the four boundary vertices nearest a right
        angle, or at four pinned ones), or on the polygon of its pinned boundary vertices (at
        least 3); holes stay holes (Theorem 5.1); each such island reports ``bijective``.

    Returns
    -------
    UnwrapResult

    Raises
    ------
    InvalidMeshError for a mesh that cannot be read, OptionError (a ValueError) for bad
    options, CancelledError when cancelled.
    """
    opts = unwrap_options(options, **values)
    if isinstance(seams, str) or opts.adds_seams:
        raise OptionError("seams_mode", "seams must be vertex pairs here: adding seams "
                          "(seams='auto') is bd_uv.unwrap's (the seam search, bd_uv.seams, "
                          "builds on this function)")
    t0 = time.perf_counter()
    V, F = check_arrays(V, F)
    m = len(F)
    keep_freed_heap(m)      # (once per process, below trim.TRIM_FACES faces)
    if opts.frames == "input-uv":
        if initial_uv is None:
            raise OptionError("frames", "frames='input-uv' needs initial_uv (m,3,2)")
        initial_uv = np.asarray(initial_uv, dtype=np.float64).reshape(m, 3, 2)
    pins = pin_arrays(pin_corners, pin_uv, m)
    conformal, unfold, one_to_one, angle, angled_res = None, True, False, None, None
    if (seams is None or not len(seams)) and not len(pins[0]) and batched_options(opts) \
            and opts.boundary == "free" and opts.stretch is None \
            and (precision is None or np.dtype(precision) == np.float64):
        if disk is None:   # one clean disk: found, solved, certified in one pass
            disk = one_disk.find(V, F, AUTO_RANKED_VERTICES if opts.bound == "auto" else None)
    else:
        disk = None
    if disk is not None:
        done, u, overlaps = one_disk.unwrap_disk(V, F, disk, None if opts.bound == "auto" else
                                                 float(opts.bound), t0, progress, cancel)
        # auto, and a conformal map within C lying over itself: the smallest C keeps the disk
        # one island where its map does not (else the general path cuts it)
        unfold = not (overlaps and opts.time_budget is None and disk_auto.searches(disk))
        if done is None and overlaps and opts.time_budget is None:
            # the conformal map wrapping round a few boundary vertices: solved again with their
            # angles capped (one island, near the conformal map), else the search below
            done = capped.unfold(V, F, disk, u, float(opts.bound), t0, progress, cancel)
        angled = None
        if (done is None and opts.bound == "auto" and opts.time_budget is None
                and len(disk.island.tris) > angle_start.FIRST_FACES):
            # a conformal start that flips, lies over itself or is far from conformal: its
            # angle start where that is better (``angle_start.better_start``), asked before the
            # search from the conformal start, which it replaces (see FIRST_FACES)
            angled = angle_start.better_start(V, disk, u)
        if done is None and (opts.bound == "auto" or overlaps) and opts.time_budget is None \
                and (angled is None or angled[0] is None):
            done = disk_auto.minimise_disk(
                V, disk, u, opts.bound_limit if opts.bound == "auto" else float(opts.bound), t0,
                progress, cancel, opts.bound)
        if (done is None and opts.bound != "auto" and opts.time_budget is None
                and angle_start.bent_first(disk, u, float(opts.bound))):
            # a number C and a conformal start flipping faces whose angle start is seldom
            # within C: bent into C first; its angle start made for the unfold only where the
            # bent map lies over itself (``angle_start.FLIPS_BENT``)
            angle = functools.partial(_angle_within, V, disk)
        elif done is None and opts.bound != "auto" and opts.time_budget is None:
            # a number C: the angle start of a disk whose conformal start is bad, certified
            # at C when within it and one simple boundary (else the general path, as before)
            v, found, _ = angle_start.better_start(V, disk, u, float(opts.bound))
            if v is not None:
                done = one_disk.fitted(F, disk, v, float(opts.bound), t0, ("angle_start",),
                                       " (from its angle start)")[0]
            if (done is None and found is not None
                    and angle_start.max_distortion(disk, found) <= angle_start.ANGLE_LIMIT):
                angle = found   # the unfold of its map before a cut starts from it
                # at once where the conformal map lies over itself (its bent map would too)
                done, none = unfold_first(V, F, disk, u, found, pins, opts, cancel, t0)
                angle = False if none else angle
        disk.forget_factors()       # the conformal solves' factorisation, not needed now
        if done is not None:
            return _tightened(V, F, done, opts, disk, whole)
        conformal_u = u
        if opts.bound == "auto":
            # a conformal start that flips, lies over itself or is far from conformal: the
            # angle start where it is better, its search's least map that does not lie over
            # itself (every other disk keeps its conformal start); with a time budget too, whose
            # conic steps keep such a map one island (``strategies.lays_out``)
            v, found, bad = angled if angled is not None else angle_start.better_start(V, disk, u)
            if v is not None:
                u, one_to_one = v, True
                if opts.time_budget is None:
                    # its search on the disk's own geometry (``disk_angle``: the general path's
                    # steps without its island problem), else the general path as before
                    angled_res = disk_angle.minimise_from_angles(V, disk, v, opts.bound_limit,
                                                                 t0, progress, cancel)
            elif bad:       # the angle start found (or none), tried before a cut as it is
                angle = False if found is None else found
            disk.forget_factors()
            if angled_res is not None and not predicted_to_fail(V, F, angled_res, disk=disk):
                return _tightened(V, F, angled_res, opts, disk, whole)
        conformal = {0: u}
    # (a disk map from its angle start flagged by ``predicted_to_fail``: the general path's
    # answer, as below)
    res = angled_res if angled_res is not None else unwrap_islands(
        V, F, [disk.island] if disk is not None else split_islands(V, F, seams, precision),
        pins, opts, initial_uv=initial_uv, face_groups=face_groups, progress=progress,
        cancel=cancel, conformal=conformal, t0=t0, disk=disk, unfold=unfold,
        one_to_one=one_to_one, angle=angle,
        over=disk is not None and opts.bound != "auto" and not overlaps)
    if (opts.bound == "auto" and disk is not None and angle is not False
            and any("angle_start" in r.flags for r in res.islands)
            and predicted_to_fail(V, F, res, disk=disk)):
        # the least C from the angle start holds in float64, but a cone-like tip (a cow's horn)
        # is shrunk below float32's step once packed, and no stretch limit keeps it one island
        # at that C (``storage.with_storage_headroom``): the conformal start's way instead, cut
        # where it lies over itself (UVs as before the angle start)
        least = _least(res)
        res = unwrap_islands(V, F, [disk.island], pins, opts, initial_uv=initial_uv,
                             face_groups=face_groups, progress=progress, cancel=cancel,
                             conformal={0: conformal_u}, t0=t0, disk=disk, unfold=unfold,
                             angle=False)
    else:
        least = None
    if opts.bound == "auto" and disk is not None and whole and _pieces(res) > (0, 1):
        res = _kept_whole(V, F, disk, opts, res, least, t0, progress, cancel)
    return _tightened(V, F, res, opts, disk, whole)


def _tightened(V, F, res, opts, disk, whole):
    """``bound="auto"``'s result with each island's C as low as float32 storage allows
    (``rounding.tightened``); once, on the outermost call (``whole``), so the tries inside
    compare the Cs they always did."""
    if opts.bound != "auto" or not whole:
        return res
    return tightened(V, F, res, disk=disk)


def _angle_within(V, disk):
    """The disk's angle start (``angle_start.angle_start``) where there is one within
    ``angle_start.ANGLE_LIMIT``, else None (a number C's unfold then starts from the
    conformal map, as where ``better_start`` found none)."""
    u = angle_start.angle_start(V, disk)
    return u if u is not None and angle_start.max_distortion(disk, u) <= angle_start.ANGLE_LIMIT \
        else None


# ``_kept_whole``'s numbers C, as multiples of the least C whose map was predicted to fail
ABOVE = (1.1, 1.25, 1.5)


def _pieces(res):
    """(islands not certified, islands): the fewer the better, in that order. A disk cut by the
    overlap repair has many; one whose map lies over itself with ``overlap="fail"`` (the
    default seams' first pass) has one that failed."""
    return sum(r.status != "certified" for r in res.islands), len(res.islands)


def _least(res):
    """The largest C certified among ``res``' islands (None where none is certified)."""
    return max((r.bound_certified for r in res.islands if r.status == "certified"), default=None)


def _kept_whole(V, F, disk, opts, res, least, t0, progress, cancel):
    """A disk that ``bound="auto"`` left cut into ``res``' pieces, tried again:

    - under a time budget, the call without one (its unfold searches keep the disk whole
      where the conic steps went on from a map lying over itself and the overlap repair cut
      it): taken when it gives fewer pieces, all certified (cow.off's patches 1522/400 and
      4355/400, 408 and 406 faces: 25 and 15 pieces at C 2.45 under the command line's budget,
      1 island at C 2.52 and 7 pieces without it);
    - still cut: a number C a little above the least C (``ABOVE``; ``least``, the angle
      start's map's where it was predicted to fail once stored in float32, a cone-like tip as a
      cow's horn, and the conformal start's way cut the disk; else the pieces' largest), the
      first that gives one certified island expected to survive float32 (cow patch 2338/400:
      6 pieces at C 3.79 -> one island at C 4.07, max distortion 3.70; 4355/400: 7 -> 1 at
      2.73, max 2.48; 1578/400 stays in 25: each of its maps at 1.1-3x its least C is flagged),
      its bound asked reported as "auto", flagged "kept_whole".
    Returns the result with the fewest pieces."""
    if opts.time_budget is not None and disk_auto.searches(disk, True):
        plain = unwrap(V, F, progress=progress, cancel=cancel, disk=disk, whole=False,
                       options=dataclasses.replace(opts, time_budget=None))
        if _pieces(plain) < _pieces(res):
            res = plain
    if least is None:       # the least C of a disk its own search cut
        least = _least(res)
    for k in ABOVE if least is not None and _pieces(res) > (0, 1) else ():
        C = float(least) * k
        if C > opts.bound_limit:
            break
        one = unwrap(V, F, progress=progress, cancel=cancel, disk=disk,
                     options=dataclasses.replace(opts, bound=C, time_budget=None))
        if (len(one.islands) == 1 and one.islands[0].status == "certified"
                and not predicted_to_fail(V, F, one, disk=disk)):
            (r,) = one.islands
            res = dataclasses.replace(one, islands=[dataclasses.replace(
                r, bound_requested="auto", flags=tuple(r.flags) + ("kept_whole",))])
            break
    return dataclasses.replace(res, seconds=time.perf_counter() - t0)


def unwrap_islands(V, F, isl, pins, options, initial_uv=None, face_groups=None, progress=None,
                   cancel=None, conformal=None, t0=None, disk=None, unfold=True,
                   one_to_one=False, angle=None, over=False):
    """``unwrap`` on islands already found (``mesh.islands``, or charts of a validated mesh).

    Parameters
    ----------
    V, F : checked arrays; isl : list of mesh.Island numbered 0.. by their smallest face
    pins : (corners (p,), uv (p,2)) as ``pin_arrays`` returns
    options : UnwrapOptions (``seams_mode="marked"``); initial_uv, face_groups, progress, cancel as
        ``unwrap``'s, already checked
    conformal : dict island index -> (nv,) complex128, optional: the island's free-boundary
        conformal map as ``batched.conformal_islands`` would solve it (unit-area normalisation,
        ``_far_pairs`` pinned at 0 and 1), already known (the seam search's chart maps); only
        used where the batched path would solve it. Everything is certified from the final UVs
        as ever.
    disk : one_disk.Disk, optional, when ``isl`` is that disk's island: a certified map is
        certified by ``disk_certificate`` first (the general overlap certificate where it does
        not clear it)
    unfold : bool, an unpinned island certified at a numeric C whose UVs lie over themselves
        gets the smallest C within it (``unfolder``) before it is cut; False where that search
        was already made (``disk_auto``)
    one_to_one : bool, ``conformal`` holds the disk's angle start (``angle_start``): with
        ``bound="auto"`` its search ends at its least map that does not lie over itself. Where
        an auto map of the disk from its conformal start lies over itself, the angle start is
        tried so (``angle_unfolder``) before the island is cut
    angle : (nv,) complex128, the disk's angle start where ``angle_start.better_start`` found
        it and did not take it (False: it found none), for ``angle_unfolder`` (``unfolder`` at a
        number C); None: made there when needed (at a number C: not tried); at a number C a
        callable making it (or None) where the unfold asks for it (``angle_start.bent_first``)
    over : bool, ``conformal`` holds the disk's conformal map, which ``one_disk.unwrap_disk``
        measured over the numeric C asked (it flips, or its max distortion is over C): not
        measured again by the batched path (three_peaks.off: 1.5 ms of CPU), its start

    Returns
    -------
    UnwrapResult
    """
    t0 = time.perf_counter() if t0 is None else t0
    m = len(F)
    start = None if angle is None or angle is False else (disk.island.index, angle)
    total = float(m)
    done = 0.0
    results = []
    corner_uv = np.full((m, 3, 2), np.nan)
    face_island = np.empty(m, dtype=np.int64)
    for island in isl:
        face_island[island.faces] = island.index
    o = options
    if o.boundary != "free" or o.stretch is not None:
        batch, starts = {}, {}
    elif over:
        batch, starts = {}, {i: np.asarray(u, dtype=np.complex128) / 1.0
                             for i, u in conformal.items()}
    else:
        batch, starts = _batched(V, isl, pins, face_island, o, progress, cancel, conformal)
    for island in isl:
        share = len(island.faces) / total

        def report(frac, msg, _done=done, _share=share, _i=island.index):
            if progress is not None:
                progress(min(1.0, _done + _share * frac), f"island {_i + 1}/{len(isl)}: {msg}")
            if cancel is not None and cancel.is_set():
                raise Cancelled
        try:
            if cancel is not None and cancel.is_set():
                raise Cancelled
            if island.index in batch:
                res = batch[island.index]
                report(1.0, "the conformal map fits the bound")
            else:
                res = solve_island(island, V, pins, o, initial_uv, report, cancel,
                                    starts.get(island.index),
                                    None if disk is None else (disk.G, disk.area),
                                    None if disk is None or o.bound != "auto" else disk.ranks,
                                    one_to_one=one_to_one)
        except Cancelled:
            raise CancelledError("unwrap cancelled; nothing was changed") from None
        if res.status == "certified":
            corner_uv[island.faces] = res.uv.take(island.tris, axis=0)   # (rows: ``take``, ~4x)
        results.append(res)
        done += share
    # the disk's distortion as finish measured it from these UVs (not the batched path's own
    # arithmetic): measured once, used by both certificates
    cert = (one_disk.certify(disk, corner_uv, results[0].bound_certified,
                             None if 0 in batch else results[0].distortion)
            if disk is not None and results[0].status == "certified" else None)
    if cert is not None:
        results, certs = [dataclasses.replace(results[0], overlap_free=True)], (cert,)
    else:
        pinned = set(face_island[pins[0] // 3].tolist())
        release_memory(m)                   # the solves' freed heap, before the certificate
        results, face_island, corner_uv, certs = overlap_certificate(
            V, F, results, face_island, corner_uv, pinned, o.overlap == "cut", face_groups,
            angle_unfolder(disk, V, pins, o, cancel, angle) if o.bound == "auto"
            and disk is not None and not one_to_one and angle is not False
            else unfolder(isl, V, pins, o, cancel, start, unfold) if unfold or start
            else None)
    if progress is not None:
        progress(1.0, "done")
    return UnwrapResult(corner_uv, face_island, results, time.perf_counter() - t0, o.method,
                        certificates=certs)


def pin_arrays(pin_corners, pin_uv, m):
    """Validated pins as (corners (p,), uv (p,2)).

    Parameters
    ----------
    pin_corners : (p,) int array or None, flat corner indices into an (m,3) F
    pin_uv : (p,2) float array or None
    m : int, the number of faces
    """
    if pin_corners is None or len(pin_corners) == 0:
        return np.zeros(0, np.int64), np.zeros((0, 2))
    c = as_indices(pin_corners, "pinned corner indices").ravel()
    if pin_uv is None:
        raise InvalidMeshError(f"{len(c)} pinned corners but no pin UVs")
    uv = as_reals(pin_uv, "pinned UVs")
    if uv.size != 2 * len(c) or (uv.ndim > 1 and uv.shape[-1] != 2):
        raise InvalidMeshError(f"{len(c)} pinned corners need ({len(c)},2) pin UVs, got shape "
                               f"{uv.shape}")
    uv = uv.reshape(-1, 2)
    if np.any((c < 0) | (c >= 3 * m)):
        raise InvalidMeshError("pinned corner indices must lie in 0..3m-1 (face * 3 + corner)")
    if not np.all(np.isfinite(uv)):
        raise InvalidMeshError("pinned UVs must be finite numbers")
    return c, uv


def _batched(V, isl, pins, face_island, options, progress, cancel, conformal=None):
    """Solve every island that can go through ``batched.conformal_islands`` at once: valid,
    unpinned, BD-LSCM from the conformal start; at a fixed bound those that fit are certified
    here, with ``bound="auto"`` only their conformal maps are solved (one assembly and
    factorisation for all, 3-4x faster than per-island ``frames.lscm_map`` on nefertiti). Returns
    (results by island index, conformal starts of the islands not certified here)."""
    bound = options.bound
    if not batched_options(options):
        return {}, {}
    pinned = np.zeros(len(isl), dtype=bool)
    if len(pins[0]):
        pinned[np.unique(face_island[pins[0] // 3])] = True
    todo = [i for i in isl if i.error is None and not pinned[i.index]]
    if not todo:    # one island too: its conformal map is solved and certified here
        return {}, {}
    if progress is not None:
        progress(0.01, f"conformal maps of {len(todo)} islands")
    if cancel is not None and cancel.is_set():
        raise CancelledError("unwrap cancelled; nothing was changed")
    return conformal_islands(V, todo, None if bound == "auto" else float(bound), conformal)

