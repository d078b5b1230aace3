"""The report entry of a file or mesh with nothing certified: the shape every failure takes,
whether the mesh failed (``bd_uv.batch``) or its worker did (a limit, a crash)."""


def failed_entry(name, error, message, faces=None, seconds=None, **where):
    """A report entry with nothing certified (``where``: input, object, output, ...)."""
    return {**where, "name": name, "status": "failed", "faces": faces, "islands": [],
            "bound_certified": None, "max_distortion": None, "mean_distortion": None,
            "flipped": None, "seconds": seconds, "error": error, "message": message}
