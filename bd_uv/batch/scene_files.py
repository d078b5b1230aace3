"""One scene file (glTF, USD): every mesh unwrapped as a job, the file written back whole.

Shared by ``python -m bd_uv unwrap`` and ``batch``. Each mesh of the scene
(:mod:`bd_uv.scenes`) is one :class:`Job`; a mesh is written only when every one of its faces is
certified, and it is certified again from the UVs exactly as the format stores them (glTF:
float32 with v downwards; USD: float32). A mesh that fails keeps the UVs it had, and its entry
says so. The report names each mesh by its node paths (glTF) or prim path (USD).
"""
import copy
import hashlib
import os
import time

import numpy as np

from ..certificate import certificate_totals
from ..errors import BDError
from ..scenes import Charts, read_scene
from ..scheduling.entries import failed_entry
from .job import Job, JobOptions
from .jobs import unwrap_job, zero_area_left_out


def unwrap_scene_file(path, output, options, seams_mode=None, png=None, base=None):
    """Unwrap every mesh of ``path`` and write the scene to ``output``.

    Parameters
    ----------
    path, output : str, the scene file read and the one written (same family: glTF or USD)
    options : JobOptions (or what ``JobOptions.of`` takes): the unwrap and layout options, and
        where the UVs go (``uv_set``: glTF ``TEXCOORD_<uv_set>``; ``uv_name``: USD primvar)
    seams_mode : None | "uv" | "none" | "auto", as for OBJ files (the file's UVs give seams)
    png : str or None, ``png`` path pattern: ``<stem>-<k>.png`` per mesh is drawn beside it
    base : dict, fields every entry starts with (input, object, output)

    Returns
    -------
    list of dict, one report entry per mesh (``name``: node or prim path)
    """
    if os.path.abspath(path) == os.path.abspath(output):
        raise BDError(f"{output} would overwrite its input; choose another output")
    base = dict(base or {"input": os.path.abspath(path), "object": None, "output": None})
    options = JobOptions.of(options)
    scene = read_scene(path, uv_set=options.uv_set, uv_name=options.uv_name)
    if not scene.meshes:
        holds = getattr(scene, "holds", "")
        raise BDError(f"{path} holds no triangle or polygon mesh" + (f": {holds}" if holds else ""))
    entries, charts, seen = [], {}, {}
    for k, sm in enumerate(scene.meshes):
        where = {**base, "object": sm.name, **sm.info}
        if sm.refused:
            entries.append(failed_entry(sm.name, "SceneFileError", sm.refused, **where))
            continue
        t0 = time.perf_counter()
        key = geometry_key(sm)
        if key in seen:   # the same arrays as an earlier mesh: the same result, not solved again
            j = seen[key]
            entries.append(_reused(entries[j], scene.meshes[j], sm, where, t0))
            if j in charts:
                charts[k] = charts[j]
            continue
        seen[key] = k
        png_k = None if png is None else f"{os.path.splitext(png)[0]}-{k}.png"
        try:
            job = Job(sm.name, sm.mesh.V, sm.mesh.F, seams=_seams(sm, seams_mode, path),
                      corner_uv=sm.mesh.corner_uv, face_groups=sm.face_groups,
                      face_labels=sm.mesh.labels, uv_dtype=np.float32,   # as written
                      position_dtype=np.float32,                         # as read
                      v_down=scene.V_DOWN)
            result = unwrap_job(job, options, png=png_k)
        except BDError as exc:
            entries.append(failed_entry(sm.name, type(exc).__name__, str(exc),
                                        seconds=round(time.perf_counter() - t0, 4), **where))
            continue
        entry = {**where, **result.entry, "warnings": list(sm.warnings)}
        lay = result.layout
        zero = zero_area_left_out(result.result, len(sm.mesh.F))
        # written when every face is certified but the zero-area ones (and some face is)
        if (lay is not None and entry["status"] != "failed"
                and ((lay.face_island >= 0) | zero).all()):
            bounds = np.array([c.bound for c in lay.certificates], dtype=np.float64)
            # a duplicate face is stored with its twin's UVs and certified through its twin, as
            # ``layout`` does: counted in the island, it would overlap its twin
            dup = getattr(result.result, "duplicate_of", None)
            island = lay.face_island if dup is None else np.where(dup >= 0, -1, lay.face_island)
            charts[k] = Charts(with_neighbour_uvs(sm.mesh.F, lay.corner_uv, zero), island, bounds)
            if zero.any():   # every face with an area is certified: the mesh is
                entry.update(status="certified", error=None, message="",
                             zero_area_faces=int(zero.sum()))
                entry["warnings"].append(
                    f"{int(zero.sum())} face(s) of zero area at the float32 precision of their "
                    "positions or UVs have no shape to map or certify: their corners take the "
                    "UVs of the same vertices in neighbouring faces")
        elif entry["status"] != "failed":
            entry["warnings"].append("not every face was certified: the mesh keeps the UVs it "
                                     "had")
        entries.append(entry)
    if not charts:  # nothing certified: no file at ``output`` that looks like a result
        return entries
    stored = scene.write(output, charts)
    for k, entry in zip(range(len(scene.meshes)), entries):
        if k not in stored:
            continue
        certs, warnings = stored[k]
        entry["warnings"] += warnings
        t = certificate_totals(certs)
        entry["stored"] = {"islands": t["islands"], "certified": t["certified"],
                           "max_distortion": t["max_distortion"], "flipped": int(t["flipped"]),
                           "overlap_free": t["overlapping"] == 0}
        if t["certified"] < t["islands"]:
            bad = [c for c in certs if not c.certified]
            entry.update(status="failed", error="SceneFileError", message=(
                f"{len(bad)} of {len(certs)} island(s) fail as stored (float32, one UV per "
                f"face-vertex), so the mesh keeps the UVs it had: "
                + "; ".join(f"island {c.island}: {c.reason}" for c in bad[:3])
                + ("; ..." if len(bad) > 3 else "")))
        else:
            entry["output"] = os.path.abspath(output)
    return entries


def geometry_key(sm):
    """A digest of everything one scene mesh's unwrap reads: positions, faces, the file's UVs
    (its seams), polygons and face labels. Meshes with equal keys get the same result (a scene
    exported with every copy of a part as its own mesh: glTF-Transform's many-cubes.gltf holds
    501 equal meshes)."""
    h = hashlib.sha256()
    m = sm.mesh
    labels = getattr(m, "labels", None) or {}
    for part in ([m.V, m.F, m.corner_uv, sm.face_groups]
                 + [labels[name] for name in sorted(labels)]):
        a = None if part is None else np.ascontiguousarray(part)
        h.update(b"-" if a is None else f"{a.dtype}{a.shape}".encode() + a.tobytes())
    return h.hexdigest()


def _reused(first, first_mesh, sm, where, t0):
    """The report entry of ``sm``, whose arrays equal those of ``first_mesh`` (entry ``first``):
    its figures, status and message, under its own name, with ``same_as`` naming the mesh whose
    result it reuses."""
    entry = copy.deepcopy(first)
    own = [w for w in entry.get("warnings", []) if w not in first_mesh.warnings]
    entry.update(where, name=sm.name, same_as=first_mesh.name, warnings=list(sm.warnings) + own,
                 seconds=round(time.perf_counter() - t0, 4))
    return entry


def with_neighbour_uvs(F, corner_uv, faces):
    """``corner_uv`` (m,3,2) with the corners of ``faces`` (m,) bool given the UVs of the same
    vertex in some other face (0 where no other face has one): a zero-area face's corners then
    lie where its neighbours put them, so it adds no seam and stays (near) degenerate in UV."""
    out = np.array(corner_uv, dtype=np.float64, copy=True)
    if not faces.any():
        return out
    F = np.asarray(F, np.int64)
    have = np.repeat(~faces, 3) & np.isfinite(out.reshape(-1, 2)).all(1)
    v = F.reshape(-1)
    uv = np.zeros((int(v.max()) + 1, 2))
    uv[v[have]] = out.reshape(-1, 2)[have]
    out[faces] = uv[F[faces]]
    return out


def _seams(sm, seams_mode, path):
    """The seams of one scene mesh: where the file's UVs are discontinuous (default when it has
    UVs, or ``--seams uv``), none, or those kept by ``--seams auto``."""
    has = sm.mesh.corner_uv is not None
    if seams_mode == "uv" and not has:
        raise BDError(f"{path}: {sm.name} has no UVs, so --seams uv has nothing to cut along")
    if seams_mode == "none" or not has:
        return None
    return sm.mesh.uv_seams()
