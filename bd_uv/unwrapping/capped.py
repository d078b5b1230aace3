"""The conformal map of a disk that lies over itself round a few boundary vertices, solved again
with their angles capped (issue 21 item 2: a number C whose conformal map overlaps).

A flip-free conformal map lies over itself where it wraps round a boundary vertex: the UV angles
of its faces there add up to 2 pi or more. That is a saddle at the boundary (a 3D angle sum over
2 pi, which a conformal map keeps), or the discrete map's own error at a deep notch
(three_peaks' 554-face centre: 0.89 x 2 pi in 3D, 1.09 x 2 pi in UV). On 42 overlapping disks
cut from the shared meshes, 1 or 2 such vertices each (all but one).

Where one boundary vertex's UV angles reach 2 pi, the faces' corner angles at the boundary
vertices whose UV angles reach CAP x 2 pi are scaled down by CAP x 2 pi over that sum (the rest
of each face's angles given to its other corners pro rata), each such face rebuilt from its
angles at its own area, and the conformal map of these shapes solved (the same system of other
coefficients, the same pins and elimination order: ``one_disk.conformal``); its UVs are
certified against the true faces by the disk certificate (no flip, max distortion within C, one
simple boundary: ``one_disk.fitted``; asked only of a map whose boundary vertices all have UV
angles below 2 pi). Up to ATTEMPTS
solves, each scaling further the vertices that still reach CAP x 2 pi (by the inverse of the
share of the last scaling their UV angles followed: RESPONSE).

The map stays near the conformal one (only the capped vertices' faces are asked to change; its
max distortion is there): on those 42 disks at C = 5, 33 unfolded so (11 in main by the bound
search alone, 13 with its early stops), 3 more by the search after it (``disk_auto``); on the
13 that the search unfolds too, means from 2.4 % below the search's to 0.04 % above it (CAP
0.95 unfolded 31 so; a first scaling twice as deep, 31; without the secant, 33 in more solves:
three_peaks:554 in 3, 4.1-4.6 ms against 3.3-3.5).

Where it does not certify, ``disk_auto.minimise_disk``'s search follows.
"""
import numpy as np

from ..geometry import corner_angles, gradient_operators
from .one_disk import conformal, fitted, report_step

__all__ = ["unfold"]

CAP = 0.97          # a boundary vertex whose UV angles reach CAP x 2 pi is capped there
RESPONSE = 0.25     # a scaling the UV angles followed by less is taken as this share
ATTEMPTS = 3        # solves at most


def from_angles(A, area):
    """Local corners (m,3) complex of triangles with the corner angles A (m,3) (each row adding
    up to pi) and the areas ``area`` (m,): corner 0 at 0, corner 1 on the positive real axis
    (the sides are as the sines of their opposite angles)."""
    s = np.sin(A)
    Z = np.zeros(A.shape, dtype=np.complex128)
    Z[:, 1] = s[:, 2]
    Z[:, 2] = s[:, 1] * np.exp(1j * A[:, 0])
    return Z * np.sqrt(area / (0.5 * s[:, 2] * s[:, 1] * np.sin(A[:, 0])))[:, None]


def unfold(V, F, disk, u, C, t0, progress=None, cancel=None):
    """The disk's conformal map with the angles capped at the boundary vertices round which the
    conformal map u (nv,) complex (``one_disk.unwrap_disk``'s) wraps, certified at C.

    Returns
    -------
    UnwrapResult (one island flagged "angles_capped" and "unfolded", certified at C), or None:
    no boundary vertex to cap, or no map of ATTEMPTS certified

    Raises
    ------
    CancelledError when ``cancel`` is set after a progress report
    """
    isl = disk.island
    tris, loop, nv = isl.tris, isl.loops[0], len(isl.vertices)
    A3 = corner_angles(disk.Z)
    scale = np.ones(nv)
    onb = np.zeros(nv, dtype=bool)
    onb[loop] = True
    theta = np.bincount(tris.ravel(), corner_angles(u.take(tris)).ravel(), nv)
    before = None           # the UV angles and the scales before the last solve
    last = None             # the scales at the faces' corners of the last solve
    for _ in range(ATTEMPTS):
        # capped where some vertex is wrapped round (else the map lies over itself elsewhere)
        wraps = onb & (theta >= CAP * 2.0 * np.pi)
        if not (onb & (theta >= 2.0 * np.pi)).any():
            return None
        report_step(progress, cancel, 0.1, f"island 1/1: the conformal map wraps round "
                    f"{int(wraps.sum())} boundary vertices: their angles capped")
        power = np.ones(nv)
        if before is not None:
            # the share of the last scaling that the UV angles followed (the conformal map
            # spreads it over the neighbours): the next one by its inverse (secant), at most
            # 1 / RESPONSE
            with np.errstate(invalid="ignore", divide="ignore"):
                took = np.log(theta / before[0]) / np.log(scale / before[1])
            power = np.where(np.isfinite(took) & (scale < before[1]),
                             1.0 / np.clip(took, RESPONSE, 1.0), 1.0)
        before = (theta, scale.copy())
        scale[wraps] *= (CAP * 2.0 * np.pi / theta[wraps]) ** power[wraps]
        at = scale.take(tris)
        faces = np.flatnonzero((at < 1.0).any(axis=1))
        s = at.take(faces, axis=0)
        A = A3[faces] * s
        rest = np.where(s < 1.0, 0.0, A)            # the corners not capped take the rest
        share = rest.sum(axis=1)
        A += rest * ((np.pi - A.sum(axis=1)) / np.where(share > 0, share, 1.0))[:, None]
        none = share <= 0                           # every corner capped: all scaled to pi
        A[none] *= (np.pi / A[none].sum(axis=1))[:, None]
        Z, G = disk.Z.copy(), disk.G.copy()
        Z[faces] = from_angles(A, disk.area[faces])
        G[faces] = gradient_operators(Z[faces])
        # the system of the last solve patched and its factor refilled where a face's scales
        # changed (each face's numbers are its own row's: the same bits as anew)
        u = conformal(V, disk, Z, G, disk.ranks, rebuilt=None if last is None else
                      (at != last).any(axis=1).nonzero()[0])
        last = at
        theta = np.bincount(tris.ravel(), corner_angles(u.take(tris)).ravel(), nv)
        if (onb & (theta >= 2.0 * np.pi)).any():    # still round a vertex: not one-to-one
            continue
        # (else, if it does not certify, capping more does not help: the loop ends above)
        done = fitted(F, disk, u, C, t0, ("angles_capped", "unfolded"),
                      f" (unfolded: the angles capped at {int((scale < 1.0).sum())} "
                      f"boundary vertices)")[0]
        if done is not None:
            report_step(progress, cancel, 1.0, "island 1/1: unfolded")
            if progress is not None:
                progress(1.0, "done")
            return done
    return None
