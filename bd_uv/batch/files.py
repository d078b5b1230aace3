"""Folder mode: which files a batch takes, where their outputs go, and one file's work.

``input_files`` and ``plan`` turn the command line's inputs into :class:`FileTask` s;
``_unwrap_file`` is what a worker runs for one file (read, unwrap, write the OBJ and PNG; a .blend
goes through the Blender script, ``_unwrap_blend``); ``run_tasks`` hands the files out, largest
first, to a local pool or a Dask cluster (``bd_uv.scheduling``).
"""
import importlib.util
import json
import os
import subprocess
import sys
import tempfile
import time
import traceback
from dataclasses import dataclass

from ..arguments import pack_flags
from ..errors import BDError
from ..meshio import AS_TRIANGLES, load_mesh, polygons_as_triangles, welded_entry, \
    write_unwrapped
from ..scenes import BLENDER_SUFFIXES, SCENE_SUFFIXES, blender_command
from ..scheduling import run_pool
from ..scheduling.atomic import atomic_path
from ..scheduling.cluster import run_dask
from .job import Job, JobOptions
from .jobs import ZERO_AREA_NOTE, failed_entry, unwrap_job, zero_area_only
from .scene_files import unwrap_scene_file

MESH_SUFFIXES = (".obj", ".off", ".ply")
BLEND_SUFFIX = ".blend"
# Of the formats Blender reads, the core reads STL itself (welded: STL splits every vertex) and
# writes it as an OBJ, as `bd-uv unwrap part.stl -o part.obj` does: no Blender needed.
CORE_READS = (".stl",)
# The Blender script of the extension: next to bd_uv/ in a clone or an installed extension; a pip
# install of bd-uv has only the core, so .blend files there need BD_UV_BLENDER_SCRIPT.
SCRIPT = os.environ.get("BD_UV_BLENDER_SCRIPT") or os.path.join(
    os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__)))), "scripts",
    "bd_uv_batch.py")


@dataclass(frozen=True)
class FileTask:
    """One input file and where its outputs go."""
    path: str
    output: str
    png: str = None


def _unwrap_file(task, options, seams_mode):
    """Worker: read ``task.path``, unwrap, write the OBJ (and PNG). Returns the report entries."""
    t0 = time.perf_counter()
    base = {"input": os.path.abspath(task.path), "object": None, "output": None}
    try:
        ext = os.path.splitext(task.path)[1].lower()
        if ext in BLENDER_SUFFIXES and ext not in CORE_READS:   # FBX, Alembic, Collada
            return _unwrap_blend(task, options, base, seams_mode)
        if ext in SCENE_SUFFIXES:     # glTF and USD: read and written whole by bd_uv.scenes
            return unwrap_scene_file(task.path, task.output, options, seams_mode, png=task.png,
                                     base=base)
        mesh = load_mesh(task.path)
        seams = None
        if seams_mode == "uv" or (seams_mode in (None, "auto", "needed") and mesh.corner_uv is not None):
            if mesh.corner_uv is None:
                raise BDError(f"{task.path} has no UVs, so --seams uv has nothing to cut along")
            seams = mesh.uv_seams()
        job = Job(mesh.name, mesh.V, mesh.F, seams=seams, corner_uv=mesh.corner_uv,
                  face_labels=mesh.labels, face_groups=mesh.face_groups)
        result = unwrap_job(job, options, png=task.png)
        entry = {**base, **welded_entry(mesh), **result.entry}
        zero = zero_area_only(result.result, result.layout, len(mesh.F))
        if zero is not None:   # every face with an area certified: the mesh is (as a scene's)
            entry.update(status="certified", error=None, message="",
                         zero_area_faces=int(zero.sum()))
            entry.setdefault("warnings", []).append(ZERO_AREA_NOTE.format(int(zero.sum())))
        if entry["status"] != "failed":
            uv, F_uv = result.layout.vertex_uv(mesh.F, fill=zero)
            split = polygons_as_triangles(mesh, F_uv)
            if split:
                entry["polygons_as_triangles"] = split
                entry.setdefault("warnings", []).append(
                    f"{split} polygon(s) written as their triangles: {AS_TRIANGLES}")
            with atomic_path(task.output) as tmp:
                write_unwrapped(tmp, task.path, mesh, uv, F_uv)
            entry["output"] = os.path.abspath(task.output)
        return [entry]
    except Exception as exc:  # one bad file never stops the rest: everything goes in its entry
        entry = failed_entry(os.path.splitext(os.path.basename(task.path))[0],
                             type(exc).__name__, str(exc),
                             seconds=round(time.perf_counter() - t0, 4), **base)
        if not isinstance(exc, (BDError, OSError)):
            entry["traceback"] = traceback.format_exc()
        return [entry]


def _unwrap_blend(task, options, base, seams_mode=None):
    """A .blend (or FBX, Alembic, Collada) goes through the Blender script in a child
    process (it needs ``bpy``); ``seams_mode`` is the batch's ``--seams`` (None: not given)."""
    if importlib.util.find_spec("bpy") is None:
        raise BDError(f"{task.path}: reading {os.path.splitext(task.path)[1]} files needs the bpy "
                      f"module (pip install bpy) or Blender itself: {blender_command(task.path)}")
    if not os.path.isfile(SCRIPT):
        raise BDError(f"{task.path}: reading .blend files needs the extension's "
                      f"scripts/bd_uv_batch.py, not found at {SCRIPT}: set "
                      "BD_UV_BLENDER_SCRIPT to it (a pip-installed bd-uv has only the core)")
    with tempfile.TemporaryDirectory() as tmp:
        report = os.path.join(tmp, "report.json")
        cmd = [sys.executable, SCRIPT, task.path, "--", "--output", task.output,
               "--report", report, *_script_options(options, seams_mode)]
        if task.png:
            cmd += ["--png", os.path.dirname(task.png), "--png-prefix",
                    os.path.splitext(os.path.basename(task.png))[0] + "-"]
        proc = subprocess.run(cmd, capture_output=True, text=True)
        if not os.path.exists(report):
            tail = (proc.stderr or proc.stdout).strip().splitlines()[-5:]
            raise BDError(f"{task.path}: the Blender script failed (exit {proc.returncode}): "
                          + " | ".join(tail))
        with open(report, encoding="utf-8") as fh:
            items = json.load(fh)["items"]
    if not items:
        raise BDError(f"{task.path} holds no mesh object with faces")
    return [{**base, **item, "input": base["input"]} for item in items]


def _script_options(options, seams_mode=None):
    """``options`` (JobOptions) and the batch's ``--seams`` (``seams_mode``: "uv" and "none" are
    the script's too; None: the options' own mode) as the Blender script's command-line flags."""
    o = JobOptions.of(options).unwrap
    out = ["--method", o.method, "--bound", str(o.bound), "--frames", o.frames,
           "--bound-limit", str(o.bound_limit), "--cone", o.cone]
    if not o.raise_bound:
        out.append("--no-raise")
    if o.time_budget is not None:
        out += ["--time-budget", str(o.time_budget)]
    if o.boundary != "free":
        out += ["--boundary", o.boundary]
    if o.stretch is not None:
        out += ["--stretch", str(o.stretch)]
    out += ["--seams", seams_mode if seams_mode in ("uv", "none") else
            o.seams_mode if o.seams_mode in ("needed", "auto") else "marked"]
    if not o.atlas_cuts:
        out.append("--no-atlas-cuts")
    job = JobOptions.of(options)
    if job.pack:   # packed by the script, each object into its own square
        out += (["--pack", *pack_flags(job.pack_options)] if job.pack_options is not None
                else ["--pack", "--pack-shape", "AABB", "--margin", repr(job.margin)])
    return out


def input_files(paths):
    """Expand folders (not recursively) into their mesh and scene files (OBJ, OFF, PLY, glTF,
    STL, USD, and through Blender .blend, FBX, Alembic, Collada), sorted by name.

    Files named explicitly are kept whatever their suffix (they fail in the report if unreadable);
    hidden files (such as an unfinished output's temporary name) are not taken from folders.
    """
    suffixes = MESH_SUFFIXES + SCENE_SUFFIXES + BLENDER_SUFFIXES
    files = []
    for p in paths:
        if os.path.isdir(p):
            files += sorted(os.path.join(p, f) for f in os.listdir(p)
                            if f.lower().endswith(suffixes) and not f.startswith(".")
                            and os.path.isfile(os.path.join(p, f)))
        else:
            files.append(p)
    return files


def plan(files, out_dir, png_dir=None):
    """A :class:`FileTask` per file; two inputs never share an output name."""
    tasks, used = [], set()
    for path in files:
        stem, ext = os.path.splitext(os.path.basename(path))
        low = ext.lower()   # a scene is written in its own format; a mesh file (STL too) as OBJ
        out_ext = low if low in SCENE_SUFFIXES + BLENDER_SUFFIXES and low not in CORE_READS \
            else ".obj"
        name, k = stem, 1
        while name.lower() in used:
            name = f"{stem}_{ext.lstrip('.').lower()}" if k == 1 else f"{stem}-{k}"
            k += 1
        used.add(name.lower())
        tasks.append(FileTask(path, os.path.join(out_dir, name + out_ext),
                              os.path.join(png_dir, name + ".png") if png_dir else None))
    return tasks


def run_tasks(tasks, options, seams_mode=None, jobs=1, on_done=None, scheduler=None,
              limits=None, retries=2, order=None, on_start=None):
    """Run every task: in a local pool of ``jobs`` processes (in this process when 1), or on a
    Dask cluster when ``scheduler`` is given (an address, or "local" for a LocalCluster of
    ``jobs`` workers). Files are handed out largest first.

    A worker that dies (crash, out of memory) has its file run again on another worker up to
    ``retries`` times; then the file fails (``WorkerCrashed``) and the batch goes on.

    Parameters
    ----------
    on_done : callable(i, entries, attempts), as each file finishes, in this process
    limits : scheduling.FileLimits, per-file time and memory limits, or None
    order : indices of ``tasks`` to run, or None for all (largest first either way)

    Returns
    -------
    entries : list of list of dict, per task (in task order; None for tasks not run)
    """
    results = [None] * len(tasks)

    def done(i, entries, attempts):
        if attempts > 1:
            for e in entries:
                e["attempts"] = attempts
        results[i] = entries
        if on_done is not None:
            on_done(i, entries, attempts)

    order = range(len(tasks)) if order is None else order
    order = sorted(order, key=lambda i: -_size(tasks[i].path))
    # The work of one file, looked up here at call time so that it can be replaced (tests).
    work = _unwrap_file
    if scheduler:
        run_dask(tasks, order, work, options, seams_mode, scheduler, jobs, done, limits, retries,
                 on_start=on_start)
    else:
        if on_start is not None:
            on_start(jobs)
        run_pool(tasks, order, work, options, seams_mode, jobs, done, limits, retries)
    return results


def _size(path):
    try:
        return os.path.getsize(path)
    except OSError:
        return 0
