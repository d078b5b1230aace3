"""Batch unwrapping: many meshes, one JSON report, a picture per mesh.

Shared by both entry points: ``python -m bd_uv batch`` (folders of OBJ/OFF/PLY/.blend files, one
worker process per file) and ``scripts/bd_uv_batch.py`` (the mesh objects of one .blend, inside
Blender or through the ``bpy`` module). Each mesh is a :class:`Job` of plain arrays; ``unwrap_job``
solves it with :func:`bd_uv.unwrap` and returns its report entry, so the report has the same shape
whichever way the arrays were gathered.

The unit of parallel work is a file, not an island: a file is read, solved and written by one worker
(no mesh or UV arrays travel between processes, only the small report entry), the split into islands
stays the core's own, and an asset folder has more files than a machine has cores. Files are handed
out largest first so one big mesh does not end up last.

Where the files run (a local process pool, or Dask distributed), the per-file limits, the report
on disk while the batch runs, ``--resume`` and the atomic writes of the outputs live in
``bd_uv.scheduling``; this module is what one file's job is, and the command line.
"""
import argparse
import importlib.util
import json
import os
import subprocess
import sys
import tempfile
import time
import traceback
from dataclasses import dataclass

import numpy as np

from .cli import (add_layout_options, add_solver_options, layout_kwargs, solver_kwargs,
                  split_options)
from .errors import BDError
from .layout import stored_layout
from .metrics import conformal_distortion
from .meshio import load_mesh, write_obj
from .scheduling.atomic import atomic_path, remove_stale
from .unwrapping import unwrap

MESH_SUFFIXES = (".obj", ".off", ".ply")
BLEND_SUFFIX = ".blend"
# The Blender script of the extension: next to bd_uv/ in a clone or an installed extension; a pip
# install of bd-uv has only the core, so .blend files there need BD_UV_BLENDER_SCRIPT.
SCRIPT = os.environ.get("BD_UV_BLENDER_SCRIPT") or os.path.join(
    os.path.dirname(os.path.dirname(os.path.abspath(__file__))), "scripts", "bd_uv_batch.py")


@dataclass(frozen=True)
class Job:
    """One mesh to unwrap.

    Attributes
    ----------
    name : str, the object or file name (report entry, PNG caption)
    V : (n,3) float64
    F : (m,3) int64
    seams : (s,2) int64 vertex pairs, or None
    pin_corners : (p,) int64 flat corner indices (face * 3 + corner), or None
    pin_uv : (p,2) float64, or None
    corner_uv : (m,3,2) float64 current UVs (for ``frames="input-uv"``), or None
    face_groups : (m,) int64 polygon of each triangle (a cut never splits a polygon), or None
    """
    name: str
    V: np.ndarray
    F: np.ndarray
    seams: np.ndarray = None
    pin_corners: np.ndarray = None
    pin_uv: np.ndarray = None
    corner_uv: np.ndarray = None
    face_groups: np.ndarray = None


@dataclass(frozen=True)
class JobResult:
    """The outcome of one job.

    Attributes
    ----------
    entry : dict, the job's JSON report entry
    corner_uv : (m,3,2) float64, the UVs to store (cut, packed as asked), NaN on faces not
        certified as stored
    result : UnwrapResult, or None when ``unwrap`` raised (the entry says why)
    layout : bd_uv.layout.Layout, the stored UVs and their certificates, or None
    """
    entry: dict
    corner_uv: np.ndarray
    result: object = None
    layout: object = None


def failed_entry(name, error, message, faces=None, seconds=None, **where):
    """A report entry with nothing certified (``where``: input, object, output, ...)."""
    return {**where, "name": name, "status": "failed", "faces": faces, "islands": [],
            "bound_certified": None, "max_distortion": None, "mean_distortion": None,
            "flipped": None, "seconds": seconds, "error": error, "message": message}


def _num(x):
    return None if x is None or not np.isfinite(x) else float(x)


def unwrap_job(job, options, png=None):
    """Unwrap one job; never raises (a failure goes into the entry, with a traceback if a bug).

    Parameters
    ----------
    job : Job
    options : dict, keyword arguments of :func:`bd_uv.unwrap` (``solver_kwargs``)
    png : str, optional, where to draw the UV layout (:func:`bd_uv.render.uv_layout_png`)

    Returns
    -------
    JobResult
        ``entry`` holds: name, status ("certified" | "partial" | "failed"), faces, islands
        (per-island entries of ``UnwrapResult.report``), bound_certified (the largest over the
        certified islands), max_distortion, mean_distortion (area-weighted over certified
        faces), flipped, seconds, error (exception type) and message.
    """
    t0 = time.perf_counter()
    m = int(len(job.F))
    entry = failed_entry(job.name, None, "", faces=m, seconds=0.0)
    kwargs, layout_options = split_options(options)
    if kwargs.get("frames") == "input-uv":
        kwargs["initial_uv"] = job.corner_uv
    if job.pin_corners is not None and len(job.pin_corners):
        kwargs.update(pin_corners=job.pin_corners, pin_uv=job.pin_uv)
    if job.face_groups is not None:
        kwargs["face_groups"] = job.face_groups
    try:
        if kwargs.get("frames") == "input-uv" and job.corner_uv is None:
            raise ValueError(f"{job.name} has no UVs to take frames from (--frames input-uv)")
        stretch = kwargs.pop("auto_stretch", None)
        if stretch is not None:     # --seams auto: the file's own seams are kept, more added
            from .seams import unwrap_auto
            res = unwrap_auto(job.V, job.F, seams=job.seams, bound=kwargs["bound"],
                              stretch=stretch, method=kwargs["method"], frames=kwargs["frames"],
                              cone=kwargs["cone"])[0]
        else:
            res = unwrap(job.V, job.F, seams=job.seams, **kwargs)
        layout = stored_layout(job.V, job.F, res, **layout_options)
    except Exception as exc:  # a bad mesh, or a bug: either way it stays this job's failure
        entry.update(error=type(exc).__name__, message=str(exc),
                     seconds=round(time.perf_counter() - t0, 4))
        if not isinstance(exc, (BDError, ValueError)):
            entry["traceback"] = traceback.format_exc()
        return JobResult(entry, np.full((m, 3, 2), np.nan), None)
    # Every figure below is measured on the UVs as stored (layout.certificates).
    islands = layout.island_entries(res)
    ok = [e for e in islands if e["status"] == "certified"]
    bad = [e for e in islands if e["status"] != "certified"]
    t = layout.totals()
    w = layout.face_island >= 0
    D = np.full(m, np.nan)
    if w.any():
        D[w] = conformal_distortion(job.V, np.asarray(job.F)[w], layout.corner_uv[w])
    entry["islands"] = islands
    entry["status"] = "certified" if not bad else ("partial" if ok else "failed")
    entry.update(overlapping=t["overlapping_unwrapped"], cut_edges=t["cut_edges"],
                 layout_overlaps=t["layout_overlaps"])
    if ok:
        entry.update(bound_certified=max(e["bound_certified"] for e in ok),
                     max_distortion=t["max_distortion"], mean_distortion=_num(t["mean_distortion"]),
                     flipped=int(t["flipped"]))
    if bad:
        entry["error"] = bad[0]["error"] or "IslandError"
        more = f" (and {len(bad) - 1} more failed island(s))" if len(bad) > 1 else ""
        entry["message"] = bad[0]["message"] + more
    entry["seconds"] = round(res.seconds, 4)
    if png:
        entry_png(png, entry, layout.corner_uv, D, options)
    return JobResult(entry, layout.corner_uv, res, layout)


def entry_png(path, entry, corner_uv, distortion, options):
    """Draw a job's UV layout with its report figures as the caption; records ``entry["png"]``.

    ``corner_uv`` (m,3,2) and ``distortion`` (m,) are NaN on faces that are not certified.
    """
    from .render import uv_layout_png
    entry["png"] = os.path.abspath(path)
    with atomic_path(path) as tmp:
        uv_layout_png(tmp, corner_uv, distortion, entry["bound_certified"],
                      caption(entry, options))


def caption(entry, options):
    """The figures under a PNG: what was asked, what was certified, how long it took."""
    bound = options.get("bound")
    ask = "bound auto" if bound == "auto" else f"bound {bound:g}"
    head = (f"{entry['name']}: BD-{options.get('method', 'lscm').upper()}, {ask}, "
            f"{entry['faces']} faces, {len(entry['islands'])} island(s)")
    if entry["bound_certified"] is None:
        return f"{head}\nnothing certified: {entry['message']}"[:400]
    n_ok = sum(i["status"] == "certified" for i in entry["islands"])
    lines = [head, f"certified C = {entry['bound_certified']:.4g} on {n_ok} island(s): max "
             f"distortion {entry['max_distortion']:.4f}, mean {entry['mean_distortion']:.4f}, "
             f"{entry['flipped']} flipped, "
             + (f"{entry['overlapping']} overlapping island(s) cut along {entry['cut_edges']} "
                "edges, " if entry.get("overlapping") else "")
             + f"{entry['seconds']:.2f} s"]
    if entry["status"] != "certified":
        lines.append(f"not certified: {entry['message']}"[:160])
    return "\n".join(lines)


# ---- folder mode -------------------------------------------------------------------------------

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
        if task.path.lower().endswith(BLEND_SUFFIX):
            return _unwrap_blend(task, options, base)
        mesh = load_mesh(task.path)
        seams = None
        if seams_mode == "uv" or (seams_mode in (None, "auto") and mesh.corner_uv is not None):
            if mesh.corner_uv is None:
                raise BDError(f"{task.path} has no UVs, so --seams uv has nothing to cut along")
            seams = mesh.uv_seams()
        job = Job(mesh.name, mesh.V, mesh.F, seams=seams, corner_uv=mesh.corner_uv)
        result = unwrap_job(job, options, png=task.png)
        entry = {**base, **result.entry}
        if entry["status"] != "failed":
            uv, F_uv = result.layout.vertex_uv(mesh.F)
            with atomic_path(task.output) as tmp:
                write_obj(tmp, mesh.V, mesh.F, uv, F_uv)
            entry["output"] = os.path.abspath(task.output)
        return [entry]
    except Exception as exc:  # one bad file never stops the rest: everything goes in its entry
        entry = failed_entry(os.path.splitext(os.path.basename(task.path))[0],
                             type(exc).__name__, str(exc),
                             seconds=round(time.perf_counter() - t0, 4), **base)
        if not isinstance(exc, (BDError, OSError)):
            entry["traceback"] = traceback.format_exc()
        return [entry]


def _unwrap_blend(task, options, base):
    """A .blend goes through the Blender script in a child process (it needs ``bpy``)."""
    if importlib.util.find_spec("bpy") is None:
        raise BDError(f"{task.path}: reading .blend files needs the bpy module "
                      "(pip install bpy) or Blender itself: blender -b FILE --python "
                      "scripts/bd_uv_batch.py -- ...")
    if not os.path.isfile(SCRIPT):
        raise BDError(f"{task.path}: reading .blend files needs the extension's "
                      f"scripts/bd_uv_batch.py, not found at {SCRIPT}: set "
                      "BD_UV_BLENDER_SCRIPT to it (a pip-installed bd-uv has only the core)")
    with tempfile.TemporaryDirectory() as tmp:
        report = os.path.join(tmp, "report.json")
        cmd = [sys.executable, SCRIPT, task.path, "--", "--output", task.output,
               "--report", report, *_script_options(options)]
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


def _script_options(options):
    """``options`` (unwrap keyword arguments) as the Blender script's command-line flags."""
    out = ["--method", options["method"], "--bound", str(options["bound"]),
           "--frames", options["frames"], "--bound-limit", str(options["bound_limit"]),
           "--cone", options["cone"]]
    if not options["raise_bound"]:
        out.append("--no-raise")
    if options.get("time_budget") is not None:
        out += ["--time-budget", str(options["time_budget"])]
    if options.get("boundary", "free") != "free":
        out += ["--boundary", options["boundary"]]
    if options.get("stretch") is not None:
        out += ["--stretch", str(options["stretch"])]
    return out


def input_files(paths):
    """Expand folders (not recursively) into their OBJ/OFF/PLY/.blend files, sorted by name.

    Files named explicitly are kept whatever their suffix (they fail in the report if unreadable);
    hidden files (such as an unfinished output's temporary name) are not taken from folders.
    """
    suffixes = MESH_SUFFIXES + (BLEND_SUFFIX,)
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
        out_ext = BLEND_SUFFIX if ext.lower() == BLEND_SUFFIX else ".obj"
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
    from .scheduling import run_pool
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
    if scheduler:
        from .scheduling.cluster import run_dask
        run_dask(tasks, order, options, seams_mode, scheduler, jobs, done, limits, retries,
                 on_start=on_start)
    else:
        if on_start is not None:
            on_start(jobs)
        run_pool(tasks, order, options, seams_mode, jobs, done, limits, retries)
    return results


def _size(path):
    try:
        return os.path.getsize(path)
    except OSError:
        return 0

# ---- command line ------------------------------------------------------------------------------

def add_batch_parser(subparsers):
    """Add ``batch`` to ``python -m bd_uv``'s subcommands."""
    p = subparsers.add_parser(
        "batch", help="unwrap every OBJ/OFF/PLY (and .blend) file of folders, in parallel",
        description="Unwrap many files: one output per input (OBJ with UVs; .blend with the UV "
                    "maps written), a JSON report, optional PNGs. Exit 0 only if every mesh was "
                    "certified; a file that fails never stops the others.")
    p.add_argument("inputs", nargs="+", metavar="INPUT",
                   help="mesh files or folders (their .obj/.off/.ply/.blend files, not recursive)")
    p.add_argument("-o", "--output", required=True, metavar="OUT_DIR", help="output folder")
    add_solver_options(p)
    add_layout_options(p)
    p.add_argument("--seams", choices=("uv", "none", "auto"), default=None,
                   help="uv: cut where an OBJ's UVs are discontinuous (default when it has vt); "
                        "none: islands are the mesh's components; auto: add seams where needed")
    p.add_argument("--jobs", type=_positive_int, default=os.cpu_count() or 1,
                   help="worker processes, one file each (default: the number of cores); with "
                        "--scheduler local, the LocalCluster's workers")
    p.add_argument("--scheduler", metavar="ADDRESS",
                   help="run on Dask distributed: a scheduler address (tcp://host:8786), or "
                        "'local' to start a LocalCluster of --jobs workers (needs the cluster "
                        "extra); default: a local process pool")
    p.add_argument("--resume", action="store_true",
                   help="keep the files the report (and its journal) already certifies for the "
                        "same input content and options, with their outputs unchanged; run the "
                        "rest")
    p.add_argument("--file-timeout", type=_positive_float, metavar="SECONDS",
                   help="fail a file that takes longer than this (it runs in a child process "
                        "that is killed); the batch goes on")
    p.add_argument("--memory-limit", type=_memory, metavar="SIZE",
                   help="fail a file whose process uses more resident memory than this "
                        "(e.g. 4GB, 800MB)")
    p.add_argument("--retries", type=_non_negative_int, default=2,
                   help="times a file is run again after its worker died (default 2; a remote "
                        "scheduler keeps its own allowed-failures)")
    p.add_argument("--report", help="JSON report path (default OUT_DIR/report.json)")
    p.add_argument("--png", metavar="DIR", help="write a picture of each UV layout into DIR")
    p.set_defaults(func=run_batch)
    return p


def _positive_float(text):
    try:
        value = float(text)
    except ValueError:
        value = 0.0
    if not value > 0:
        raise argparse.ArgumentTypeError(f"must be a number > 0, not {text!r}")
    return value


def _non_negative_int(text):
    if not text.isdigit():
        raise argparse.ArgumentTypeError(f"must be a whole number >= 0, not {text!r}")
    return int(text)


def _memory(text):
    """``4GB``, ``800MB``, ``512M``, ``2e9`` (bytes) -> bytes."""
    units = {"": 1, "K": 2**10, "M": 2**20, "G": 2**30, "T": 2**40}
    t = text.strip().upper().removesuffix("IB").removesuffix("B")
    unit = t[-1] if t and t[-1] in units else ""
    try:
        value = float(t[:-1] if unit else t) * units[unit]
    except ValueError:
        value = 0
    if not value > 0:
        raise argparse.ArgumentTypeError(f"must be a size such as 4GB or 800MB, not {text!r}")
    return int(value)


def _positive_int(text):
    try:
        value = int(text)
    except ValueError:
        value = 0
    if value < 1:
        raise argparse.ArgumentTypeError(f"must be a whole number >= 1, not {text!r}")
    return value


def run_batch(args):
    """``python -m bd_uv batch``: returns the exit code (0: all certified, 1: some failed)."""
    from .scheduling import FileLimits, Ledger, Progress, options_sha256, read_previous, reusable
    files = input_files(args.inputs)
    if not files:
        print(f"error: no .obj/.off/.ply/.blend files in {' '.join(args.inputs)}",
              file=sys.stderr)
        return 2
    os.makedirs(args.output, exist_ok=True)
    if args.png:
        os.makedirs(args.png, exist_ok=True)
    tasks = plan(files, args.output, args.png)
    options = {**solver_kwargs(args), **layout_kwargs(args)}
    if args.seams == "auto":
        if args.bound == "auto":
            print("error: --seams auto needs a numeric --bound C", file=sys.stderr)
            return 2
        if args.boundary != "free":
            print("error: --seams auto makes free-boundary charts; use --boundary free with it",
                  file=sys.stderr)
            return 2
        options["auto_stretch"] = 2.0 if args.stretch is None else args.stretch
    report_path = args.report or os.path.join(args.output, "report.json")
    collisions = [t for t in tasks if os.path.abspath(t.output) == os.path.abspath(t.path)]
    if collisions:
        print(f"error: {collisions[0].output} would overwrite its input; choose another -o",
              file=sys.stderr)
        return 2
    limits = FileLimits(args.file_timeout, args.memory_limit)
    if limits and not hasattr(os, "fork"):
        print("error: --file-timeout and --memory-limit need os.fork (Linux, macOS)",
              file=sys.stderr)
        return 2

    results = [None] * len(tasks)   # per task: its entries, once finished (or carried over)
    carried = set()
    if args.resume:  # a killed run may have left temporary files; its journal lists the rest
        for folder in {args.output, args.png} - {None}:
            remove_stale(folder)
        previous = read_previous(report_path)
        key = options_sha256(options, args.seams)
        for i, t in enumerate(tasks):
            entries = previous.get(os.path.abspath(t.path))
            if reusable(t, entries, key):
                results[i] = entries
                carried.add(i)
    todo = [i for i in range(len(tasks)) if i not in carried]
    setup = {"scheduler": args.scheduler or "pool", "jobs": args.jobs}
    t0 = time.perf_counter()
    interrupted = False

    def build(final=False):
        items = [e for entries in results if entries for e in entries]
        now = time.perf_counter()
        return batch_report(items, options, now - t0, files=files,
                            interrupted=interrupted, running=not final,
                            resumed=[results[i] for i in sorted(carried)],
                            files_run=sum(r is not None for r in results) - len(carried),
                            startup=(ready[0] if ready else now) - t0,
                            working=(last[0] if last else now) - (ready[0] if ready else now),
                            **setup)

    ledger = Ledger(report_path, build)
    ledger.start([(os.path.abspath(tasks[i].path), results[i]) for i in sorted(carried)])
    progress = Progress(len(todo), weight=sum(_size(tasks[i].path) for i in todo))

    def on_done(i, entries, attempts):
        last[:] = [time.perf_counter()]
        results[i] = entries
        ledger.record(os.path.abspath(tasks[i].path), entries)
        progress.advance("\n".join(item_line(e) for e in entries),
                         [e["status"] for e in entries], _size(tasks[i].path))

    ready, last = [], []

    def on_start(workers):
        setup["jobs"] = workers
        ready.append(time.perf_counter())

    if carried:
        print(f"--resume: {len(carried)} file(s) already certified with these options, "
              f"{len(todo)} to run")
    try:
        run_tasks(tasks, options, args.seams, jobs=args.jobs, on_done=on_done,
                  scheduler=args.scheduler, limits=limits, retries=args.retries, order=todo,
                  on_start=on_start)
    except KeyboardInterrupt:  # keep what is done: its outputs are written, the report says so
        interrupted = True
    report = build(final=True)
    ledger.finish(report)
    progress.close()
    s = report["summary"]
    print(f"{s['files']} file(s), {s['meshes']} mesh(es): {s['certified']} certified, "
          f"{s['partial']} partial, {s['failed']} failed"
          + (f", {s['not_run']} not run (interrupted)" if interrupted else "")
          + (f", {s['resumed']} file(s) kept from the earlier run" if carried else "")
          + f"; {s['overlapping_islands']} overlapping island(s), "
            f"{s['layout_overlaps']} overlapping island pair(s)"
          + f"; {s['seconds']:.1f} s"
          + (f" ({s['startup_seconds']:.1f} s to start)" if args.scheduler else "")
          + f" on {s['jobs']} {setup['scheduler']} worker(s): "
          f"{s['files_per_minute']:.1f} files/min, {s['faces_per_minute']:.0f} faces/min; "
          f"report: {report_path}")
    if interrupted:
        return 130
    return 0 if s["certified"] == s["meshes"] and s["meshes"] > 0 else 1


def batch_report(items, options, wall, jobs, files, interrupted=False, running=False,
                 resumed=(), scheduler="pool", files_run=None, startup=0.0, working=None):
    """The JSON report: options, a summary and one entry per mesh (file or .blend object).

    ``resumed`` are the entry lists of the files kept from an earlier run by ``--resume``. The
    throughput (files and faces per minute) counts only the ``files_run`` files run this time
    (default: every file with an entry, less those resumed), over the ``working`` seconds from
    the workers being ready to the last file done (default: ``wall`` less the ``startup``
    seconds spent before the workers were ready: starting a LocalCluster, connecting).
    """
    from . import __version__
    count = {k: sum(e["status"] == k for e in items) for k in ("certified", "partial", "failed")}
    seen = {e["input"] for e in items}
    kept = {id(e) for entries in resumed for e in entries}
    ran = [e for e in items if id(e) not in kept]
    working = wall - startup if working is None else working
    minutes = max(working, 1e-9) / 60.0
    if files_run is None:
        files_run = len({e["input"] for e in ran})
    return {"tool": "bd_uv batch", "version": __version__, "options": options,
            "summary": {"files": len(files), "meshes": len(items), **count,
                        "not_run": sum(os.path.abspath(f) not in seen for f in files),
                        "resumed": len(resumed), "seconds": round(wall, 3),
                        "startup_seconds": round(startup, 3),
                        "working_seconds": round(working, 3),
                        "files_per_minute": round(files_run / minutes, 2),
                        "faces_per_minute": round(sum(e["faces"] or 0 for e in ran) / minutes),
                        "overlapping_islands": sum(e.get("overlapping") or 0 for e in items),
                        "layout_overlaps": sum(e.get("layout_overlaps") or 0 for e in items),
                        "scheduler": scheduler, "jobs": jobs, "interrupted": interrupted,
                        "running": running},
            "items": items}


def item_line(e):
    """One line per mesh: status, name, size, the figures or the error."""
    name = os.path.basename(e["input"]) if e.get("input") else e["name"]
    if e.get("object"):
        name += f":{e['object']}"
    head = f"{e['status']:<9} {name}"
    if e["faces"] is not None:
        head += f": {e['faces']} faces, {len(e['islands'])} island(s)"
    if e["bound_certified"] is not None:
        head += (f", C = {e['bound_certified']:.4g}, max {e['max_distortion']:.3f}, mean "
                 f"{e['mean_distortion']:.3f}, {e['flipped']} flipped")
    if e["seconds"] is not None:
        head += f", {e['seconds']:.2f} s"
    if e.get("attempts", 1) > 1:
        head += f" (attempt {e['attempts']})"
    if e["status"] != "certified":
        head += f" -- {e['error']}: {e['message']}"
    return head
