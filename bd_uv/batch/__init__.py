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
``bd_uv.scheduling``; this package is what one mesh's job is (``job``), how it runs (``jobs``),
its picture (``picture``), one file's work and the files of a batch (``files``), the report
(``report``) and the command line (``command``).
"""
from .command import add_batch_parser, run_batch
from .files import BLEND_SUFFIX, MESH_SUFFIXES, SCRIPT, FileTask, input_files, plan, run_tasks
from .job import Job, JobOptions, JobResult
from .jobs import failed_entry, unwrap_job
from .picture import caption, entry_png
from .report import batch_report, item_line

__all__ = ["BLEND_SUFFIX", "MESH_SUFFIXES", "SCRIPT", "FileTask", "Job", "JobOptions", "JobResult",
           "add_batch_parser", "batch_report", "caption", "entry_png", "failed_entry",
           "input_files", "item_line", "plan", "run_batch", "run_tasks", "unwrap_job"]
