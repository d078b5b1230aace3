"""Freed memory handed back to the operating system between the large steps of a big mesh's
unwrap (the seam search's rounds, the certificate's overlap test).

numpy frees a large array at once, but glibc's allocator keeps what it freed from its heap for
reuse, and after the first frees of large arrays it raises its mmap threshold (up to 32 MB), so
the arrays of a 100k+ face mesh (an edge table's temporaries of 12 MB each) come from that heap
too. The seam search builds and drops such arrays every round, and the next large block (an LDL^T
factor of hundreds of MB, mapped on its own) then lands beside hundreds of MB of freed but still
resident heap: measured on a 500k-face mesh, 457 MB resident after the edge table whose arrays
hold 114 MB, 185 MB after ``malloc_trim``, which takes ~3 ms there. On other C libraries (and
below ``TRIM_FACES``) nothing is done.
"""
import contextlib
import functools
import ctypes
import ctypes.util
import sys
import threading

# Meshes from this many faces have their freed memory handed back between steps.
TRIM_FACES = 50_000
# Rows (faces, edges) of per-row arithmetic formed at a time on large meshes: every row's
# numbers are its own, so the results are the same bits whatever the chunk, and the (k,3,3)
# temporaries of a 500k-face mesh are not all held at once (certificate, seam search,
# conformal maps, LSCM geometry).
CHUNK = 65536

# While a search of at least ``TRIM_FACES`` faces runs, every block of at least this many bytes
# (an array of 1M float64) is mapped on its own and returned at its free: glibc's rule would
# otherwise raise its mmap threshold to the largest array freed (up to 32 MB), and the freed
# arrays of each step stay resident in its heap until the next ``release_memory``. Measured on a
# 500k-face mesh (benchmarks/results/issue21-mem7-2026-11-27.md), the costs being system time
# (pages faulted in afresh): unmapped 27.5 s, 360 MB; 8 MB 28.0-30.0 s, 330-339 MB; 4 MB
# 29.8-30.2 s, 333-334 MB; 2 MB 32.1-32.5 s, 331-332 MB; xatlas 25.6-26.0 s, 333-334 MB (one
# quiet session, isolate.py). 8 MB takes most of the memory for a third of 2 MB's time: the seam
# search's time is the criterion it misses at that size.
MAP_BYTES = 8 << 20
# glibc's mallopt parameters; its default trim threshold; its dynamic rule's largest mmap
# threshold (DEFAULT_MMAP_THRESHOLD_MAX on 64-bit), and the trim threshold it sets beside it.
_M_TRIM_THRESHOLD, _M_MMAP_THRESHOLD = -1, -3
_TRIM_DEFAULT = 128 * 1024
_MMAP_MAX = 32 * 1024 * 1024

_trim = None                # libc's malloc_trim, False where there is none
_mallopt = None             # libc's mallopt, False where there is none
_lock = threading.Lock()
_depth = 0                  # searches running inside ``large_blocks_mapped``
_kept = False               # ``keep_freed_heap`` has set the thresholds in this process


def release_memory(faces):
    """``malloc_trim(0)`` (glibc) when the work at hand covers at least ``TRIM_FACES`` faces."""
    global _trim
    if faces < TRIM_FACES:
        return
    if _trim is None:
        _trim = False
        if sys.platform.startswith("linux"):
            try:
                _trim = ctypes.CDLL(ctypes.util.find_library("c") or "libc.so.6").malloc_trim
                _trim.argtypes, _trim.restype = [ctypes.c_size_t], ctypes.c_int
            except (OSError, AttributeError):     # not glibc (musl has no malloc_trim)
                _trim = False
    if _trim:
        _trim(0)


def keep_freed_heap(faces):
    """Below ``TRIM_FACES`` faces, once per process: glibc's mmap and trim thresholds set where
    its own rule leaves them after a large run (32 MB, 64 MB; ``large_blocks_mapped`` restores
    the same), so a small unwrap's arrays of more than 128 kB are served from the heap and what
    it frees stays there for its next arrays, instead of being mapped and unmapped (or the heap
    trimmed) many times a call, each page faulted in again: 300-3,000 page faults a C = 5 call
    on 1-4k-face disks (~1.5 us each here), none after the first call with the thresholds set
    (benchmarks/results/issue21-c5x25-2026-11-28.md). Nothing is done where glibc's mallopt is
    missing, or while a large search holds its own thresholds. Which memory serves a block never
    changes a value computed in it."""
    global _kept
    if _kept or faces >= TRIM_FACES:
        return
    mallopt = _libc_mallopt()
    with _lock:
        if _depth == 0 and not _kept:
            _kept = True
            if mallopt:
                mallopt(_M_MMAP_THRESHOLD, _MMAP_MAX)
                mallopt(_M_TRIM_THRESHOLD, 2 * _MMAP_MAX)


def _libc_mallopt():
    """glibc's ``mallopt`` (``int mallopt(int, int)``), or False where there is none."""
    global _mallopt
    if _mallopt is None:
        _mallopt = False
        if sys.platform.startswith("linux"):
            try:
                _mallopt = ctypes.CDLL(ctypes.util.find_library("c") or "libc.so.6").mallopt
                _mallopt.argtypes, _mallopt.restype = [ctypes.c_int, ctypes.c_int], ctypes.c_int
            except (OSError, AttributeError):     # not glibc
                _mallopt = False
    return _mallopt


@contextlib.contextmanager
def large_blocks_mapped(faces):
    """Within the block, glibc maps every allocation of at least ``MAP_BYTES`` on its own (and
    unmaps it at its free), when the work covers at least ``TRIM_FACES`` faces; elsewhere, and
    below that size, nothing changes.

    On the way out the thresholds are left where glibc's own rule leaves them after a large run
    (mmap threshold 32 MB, trim threshold 64 MB): a fixed threshold turns that rule off for the
    rest of the process (glibc has no call that turns it back on), and after the arrays of a
    100k+ face mesh it has reached its ceiling anyway. Nested and concurrent blocks set the
    thresholds once, and the last one out restores them. Which memory a block is served from
    never changes a value computed in it.
    """
    global _depth
    mallopt = _libc_mallopt() if faces >= TRIM_FACES else False
    if not mallopt:
        yield
        return
    with _lock:
        _depth += 1
        if _depth == 1:
            mallopt(_M_MMAP_THRESHOLD, MAP_BYTES)
            mallopt(_M_TRIM_THRESHOLD, _TRIM_DEFAULT)
    try:
        yield
    finally:
        with _lock:
            _depth -= 1
            if _depth == 0:
                mallopt(_M_MMAP_THRESHOLD, _MMAP_MAX)
                mallopt(_M_TRIM_THRESHOLD, 2 * _MMAP_MAX)



def maps_large_blocks(search):
    """Decorator: ``search(V, F, ...)`` runs inside ``large_blocks_mapped`` for F's faces (none
    where F has no length: ``search`` reports what is wrong with it)."""
    @functools.wraps(search)
    def run(V, F, *args, **kwargs):
        with large_blocks_mapped(len(F) if hasattr(F, "__len__") else 0):
            return search(V, F, *args, **kwargs)
    return run
