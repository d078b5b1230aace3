"""Typed errors. Every error bd_uv raises or records derives from :class:`BDError`, so a caller
(the Blender operator, the batch tool) can catch precisely and show ``str(error)`` to the user: each
message names the problem and what to do about it."""
import re


class BDError(Exception):
    """Base class of every bd_uv error."""


class InvalidMeshError(BDError):
    """The mesh as a whole cannot be read: empty, wrong shapes, face indices out of range."""


class CancelledError(BDError):
    """The solve was cancelled; nothing partial is returned."""


class IslandError(BDError):
    """A problem confined to one island; the other islands are still solved.

    Attributes
    ----------
    island : int or None
        Index of the island the problem belongs to.
    faces : (k,) int array or None
        The input faces concerned (for example the zero-area ones).
    """

    def __init__(self, message, island=None, faces=None):
        super().__init__(message)
        self.island = island
        self.faces = faces

    def renumber(self, island):
        """Make this the error of island ``island``: its ``island`` and the "island N" its
        message starts with (islands are renumbered when results are merged or spliced)."""
        msg = str(self)
        if msg.startswith("island "):
            msg = re.sub(r"^island \d+", f"island {island}", msg, count=1)
        self.args = (msg,) + tuple(self.args[1:])
        self.island = island
        return self


class ClosedIslandError(IslandError):
    """The island has no boundary: it needs seams before it can be flattened."""


class NonManifoldError(IslandError):
    """An edge shared by three or more faces, or, within one island, faces that meet only at a
    vertex (bow-tie). Parts that touch only at a vertex and are otherwise separate become separate
    islands, which is not an error."""


class DegenerateFacesError(IslandError):
    """Zero-area faces (collinear or coincident vertices)."""


class NonFiniteError(IslandError):
    """NaN or infinite vertex coordinates."""


class TopologyError(IslandError):
    """The island is not a disk with holes (genus >= 1): it needs more seams."""


class OrientationError(IslandError):
    """Neighbouring faces are oriented inconsistently."""


class DuplicateFacesError(IslandError):
    """Two or more faces use the same three vertices."""


class InfeasibleError(IslandError):
    """No certified map exists within the bound limit (for example pins that force a flip)."""


class SolverError(IslandError):
    """The solver failed or its result could not be certified."""


class OverlapError(IslandError):
    """The island's UVs lie over themselves (its UV boundary is not simple); cut it or mark seams."""


class PackError(BDError):
    """The charts cannot be packed with the options given (bad options, a chart larger than a
    UDIM tile at the texel density asked for, or no layout that passes the layout certificate)."""


class OptionError(BDError, ValueError):
    """An unwrap option out of its range, or options that cannot go together
    (``bd_uv.options.UnwrapOptions``). A ValueError too, as bad options always were.

    Attributes
    ----------
    option : str, the option's name (the first one named when two cannot go together)
    """

    def __init__(self, option, message):
        super().__init__(message)
        self.option = option


class SceneFileError(BDError):
    """A scene file (glTF, USD) cannot be read or written as asked; the message names the file
    and the node, mesh or prim concerned."""


class MissingExtraError(BDError):
    """A format needs an optional package that is not installed; the message names the extra."""


LFS_POINTER = b"version https://git-lfs.github.com/spec/"


def refuse_lfs_pointer(path, error=InvalidMeshError):
    """Raise ``error`` naming a Git LFS pointer: a small text file a repository cloned without
    its LFS objects holds in the asset's place (NVIDIA warp's example .usd files), which every
    reader would otherwise refuse in its own words ("not a USD stage USD can open (Error in
    'pxrInternal_...::UsdStage::Open' ...)", "the file holds no faces"). Unreadable: left to
    the reader, which says why."""
    try:
        with open(path, "rb") as fh:
            head = fh.read(len(LFS_POINTER))
    except OSError:
        return
    if head == LFS_POINTER:
        raise error(f"{path}: a Git LFS pointer, not the file itself (the repository was cloned "
                    f"without its LFS objects): fetch them (git lfs pull) and run again")
