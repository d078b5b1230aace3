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
import ctypes
import ctypes.util
import sys

# Meshes from this many faces have their freed memory handed back between steps.
TRIM_FACES = 50_000
# Rows (faces, edges) of per-row arithmetic formed at a time on large meshes: every row's
# numbers are its own, so the results are the same bits whatever the chunk, and the (k,3,3)
# temporaries of a 500k-face mesh are not all held at once (certificate, seam search,
# conformal maps, LSCM geometry).
CHUNK = 65536

_trim = None                # libc's malloc_trim, False where there is none


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
