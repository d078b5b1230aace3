"""Atomic file writes: write to a temporary name in the same folder, then rename over the target.

A reader (or a ``--resume``) sees either the previous file or the complete new one, never a file
cut short by a crash or a killed worker: ``os.replace`` is atomic on one filesystem (POSIX rename,
Windows MoveFileEx). The temporary name starts with a dot, so folder scans skip it, and keeps the
target's suffix, so writers that pick a format by suffix (matplotlib's ``savefig``) still work.
"""
import contextlib
import hashlib
import os
import secrets

TMP_MARK = ".bd-uv-tmp-"


@contextlib.contextmanager
def atomic_path(path):
    """Yield a temporary path next to ``path``; on a clean exit rename it to ``path``.

    On an exception the temporary file is removed and ``path`` is left as it was.

    >>> with atomic_path("out/a.obj") as tmp:          # doctest: +SKIP
    ...     write_obj(tmp, V, F, uv, F_uv)
    """
    folder, name = os.path.split(os.path.abspath(path))
    stem, ext = os.path.splitext(name)
    os.makedirs(folder, exist_ok=True)
    tmp = os.path.join(folder, f".{stem}{TMP_MARK}{os.getpid()}-{secrets.token_hex(4)}{ext}")
    try:
        yield tmp
        os.replace(tmp, path)
    except OSError as exc:   # said in the caller's terms: the path asked for, not the temporary
        if exc.filename == tmp:
            exc.filename = path
        raise
    finally:
        if os.path.lexists(tmp):
            os.remove(tmp)


def file_sha256(path, chunk=1 << 20):
    """Hex SHA-256 of a file's bytes, or None when it cannot be read."""
    h = hashlib.sha256()
    try:
        with open(path, "rb") as fh:
            for block in iter(lambda: fh.read(chunk), b""):
                h.update(block)
    except OSError:
        return None
    return h.hexdigest()


def remove_stale(folder):
    """Remove temporary files left in ``folder`` by writes that were killed; their names."""
    try:
        names = [n for n in os.listdir(folder) if n.startswith(".") and TMP_MARK in n]
    except OSError:
        return []
    for n in names:
        with contextlib.suppress(OSError):
            os.remove(os.path.join(folder, n))
    return names
