"""A mesh's arrays checked before anything is computed on them: shapes, indices and numbers
(``check_arrays``, ``as_reals``, ``as_indices``), coordinates too large to measure
(``measurable``) and faces too thin for the precision the positions and UVs are stored in
(``thinner_than_precision``)."""
import numpy as np

from ..errors import InvalidMeshError
from ..array_calls import quiet

# A face is degenerate when twice its area is below this fraction of its longest edge squared.
DEGENERATE_RATIO = 1e-12


def check_arrays(V, F, *, share=False):
    """Validate shapes and indices; return float64 V and int64 F.

    With ``share``, arrays already of those types come back as read-only views of the caller's
    (no copy: the seam search holds V and F through its whole run, 17 MB on a 500k-face mesh);
    anything writing into them raises rather than changing the caller's mesh.

    Raises
    ------
    InvalidMeshError
    """
    V = np.asarray(V)
    F = np.asarray(F)
    if V.ndim != 2 or V.shape[1] != 3:
        raise InvalidMeshError(f"vertices must be an (n,3) array, got shape {V.shape}")
    if F.size == 0:
        raise InvalidMeshError("the mesh has no faces: nothing to unwrap")
    if F.ndim != 2 or F.shape[1] != 3:
        raise InvalidMeshError(f"faces must be an (m,3) array of triangles, got shape {F.shape}; "
                               "triangulate n-gons first")
    F = _shared(F) if share and F.dtype == np.int64 else as_indices(F, "face indices")
    out = (F < 0) | (F >= len(V))
    if np.logical_or.reduce(out, axis=None):        # (the faces named only then)
        bad = np.flatnonzero(out.any(axis=1))
        raise InvalidMeshError(f"{len(bad)} face(s) use vertex indices outside 0..{len(V) - 1} "
                               f"(faces {_some(bad)}); fix the face list")
    return (_shared(V) if share and V.dtype == np.float64 else as_reals(V, "vertex coordinates"),
            F)


def _shared(x):
    """A read-only view of ``x``."""
    x = x.view()
    x.flags.writeable = False
    return x


def as_reals(x, what):
    """``x`` as float64, or InvalidMeshError naming ``what`` when it is not real numbers (text,
    complex numbers: nothing is parsed or dropped silently). NaN and inf pass."""
    x = np.asarray(x)
    if x.dtype.kind not in "biufO":
        raise InvalidMeshError(f"{what} must be real numbers, got {x.dtype}")
    try:
        return x.astype(np.float64)
    except (TypeError, ValueError) as exc:
        raise InvalidMeshError(f"{what} must be real numbers ({exc})") from None


def as_indices(x, what):
    """``x`` as int64 indices, or InvalidMeshError naming ``what`` when a value is not an integer
    (fractions, NaN, text: never truncated or cast silently)."""
    x = np.asarray(x)
    if x.dtype.kind in "iu":
        return x.astype(np.int64)
    f = as_reals(x, what)
    if not np.all(np.isfinite(f)) or np.any(f != np.round(f)):
        raise InvalidMeshError(f"{what} must be integers")
    return f.astype(np.int64)


def _some(idx, k=8):
    idx = np.asarray(idx)
    s = ", ".join(str(int(i)) for i in idx[:k])
    return s + (f", ... ({len(idx)} in all)" if len(idx) > k else "")


#: the largest coordinate magnitude a face may have: the seam search forms fourth powers of
#: coordinates (area-weighted second moments), which overflow float64 near 1e77 (a disk scaled to
#: 1e80 ended in LinAlgError out of the Fiedler split's principal axes); beyond it a face is refused
#: by name as too large to measure, as a non-finite one is
MEASURABLE = 1e60
TOO_LARGE = "coordinates beyond 1e60 (too large to measure)"   # how messages say it


def measurable(P):
    """(m,) bool: faces (corners ``P`` (m,3,3)) whose coordinates are finite and at most
    ``MEASURABLE`` in magnitude."""
    with quiet("invalid"):
        return np.all(np.abs(P) <= MEASURABLE, axis=(1, 2))


def thinner_than_precision(P, A, lmax2, precision):
    """(m,) bool: faces (corners ``P`` (m,3,3), areas ``A``, longest edges squared ``lmax2``)
    too thin for ``precision``, the float type the positions were stored in and the UVs are
    written in (``np.float32`` for glTF, USD, Blender); None or float64: none. Their height,
    twice the area over the longest edge, is below

    - one step of ``precision`` at their largest coordinate: three points that precision cannot
      tell from a line; or
    - one step of ``precision`` in the unit square's upper half (2^-24 for float32) times the
      square root of the mesh's area (the faces ``A`` given): at the largest scale a map of the
      mesh into the unit square has on average (its faces keeping their 3D areas, all of the
      square covered), the face is less than one UV step high, so no float32 UVs keep it from
      flipping or collapsing wherever it is packed. usd-wg's tractor body has one such face
      (3.7e-7 high at coordinates up to 2.85, 1.6 position steps, in 195 square units: 0.45 UV
      step); it failed its island as stored in about one run of four, by where it was packed.
    """
    if precision is None or np.dtype(precision) == np.float64:
        return np.zeros(len(A), dtype=bool)
    with quiet("invalid", "over", "divide"):
        step = np.spacing(np.abs(P).max(axis=(1, 2)).astype(precision)).astype(np.float64)
        total = float(np.sum(A[np.isfinite(A)]))
        uv_step = float(np.spacing(np.asarray(0.5, dtype=precision))) * np.sqrt(total)
        return ~(2 * A > np.maximum(step, uv_step) * np.sqrt(lmax2))
