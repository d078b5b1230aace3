"""Running a batch's files: where each file runs, within which limits, and what is on disk.

- ``worker``: what runs for one file (``run_file``): ``bd_uv.batch``'s unwrap and write, the
  hashes ``--resume`` checks, and the per-file time and memory limits (``FileLimits``);
- ``pool``: a local process pool (the default);
- ``cluster``: Dask distributed, a remote scheduler or a LocalCluster (optional extra);
- ``ledger``: the report and its journal while the batch runs, and what ``--resume`` may skip;
- ``atomic``: outputs written under a temporary name, then renamed;
- ``progress``: the per-mesh lines and the progress bar.
"""
from .atomic import atomic_path, file_sha256
from .ledger import Ledger, options_sha256, read_previous, reusable
from .pool import crashed_entry, run_pool
from .progress import Progress
from .worker import FileLimits, run_file

__all__ = ["FileLimits", "Ledger", "Progress", "atomic_path", "crashed_entry", "file_sha256",
           "options_sha256", "read_previous", "reusable", "run_file", "run_pool"]
