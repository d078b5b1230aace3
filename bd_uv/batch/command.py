"""``python -m bd_uv batch``: its arguments and the run (resume, journal, progress, summary).

Where the files run, the per-file limits, the report on disk while the batch runs (``Ledger``),
``--resume`` and the atomic writes live in ``bd_uv.scheduling``; this module wires them to the
command line.
"""
import argparse
import os
import sys
import time

from ..arguments import (add_layout_options, add_scene_options, add_solver_options,
                         layout_kwargs, scene_option_misuse, unwrap_options_of)
from ..scheduling import FileLimits, Ledger, Progress, options_sha256, read_previous, reusable
from ..scheduling.atomic import remove_stale
from .files import _size, input_files, plan, run_tasks
from .job import JobOptions
from .report import batch_report, item_line


def add_batch_parser(subparsers):
    """Add ``batch`` to ``python -m bd_uv``'s subcommands."""
    p = subparsers.add_parser(
        "batch", help="unwrap every mesh and scene file of folders, in parallel",
        description="Unwrap many files: one output per input (OBJ with UVs for OBJ/OFF/PLY/STL; "
                    "glTF and USD scenes written whole; .blend, FBX, Alembic and Collada "
                    "through Blender with the UV maps written), a JSON report, "
                    "optional PNGs. Exit 0 only if every mesh was "
                    "certified; a file that fails never stops the others.")
    p.add_argument("inputs", nargs="+", metavar="INPUT",
                   help="mesh or scene files, or folders (their .obj/.off/.ply/.gltf/.glb/.usd/"
                        ".usda/.usdc/.usdz/.blend/.fbx/.abc/.dae/.stl files, not recursive)")
    p.add_argument("-o", "--output", required=True, metavar="OUT_DIR", help="output folder")
    add_solver_options(p)
    add_layout_options(p)
    add_scene_options(p)
    p.add_argument("--seams", choices=("needed", "uv", "none", "auto"), default=None,
                   help="needed (the default): an OBJ's UV seams kept, the mesh repaired, seams "
                        "added only to islands that cannot be certified as they are; uv: cut "
                        "where an OBJ's UVs are discontinuous; none: islands are the mesh's "
                        "components; auto: search seams on every island")
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
    files = input_files(args.inputs)
    if not files:
        print(f"error: no mesh or scene files in {' '.join(args.inputs)}",
              file=sys.stderr)
        return 2
    misuse = scene_option_misuse(args, files)
    if misuse:
        print(f"error: {misuse}", file=sys.stderr)
        return 2
    options = JobOptions(unwrap_options_of(args), **layout_kwargs(args), uv_set=args.uv_set,
                         uv_name=args.uv_name)
    os.makedirs(args.output, exist_ok=True)
    if args.png:
        os.makedirs(args.png, exist_ok=True)
    tasks = plan(files, args.output, args.png)
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
        progress.advance("\n".join(item_line(e) + "".join(f"\n  warning: {w}" for w in
                                                           e.get("warnings", []))
                                    for e in entries),
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
