"""numpy calls without their Python wrappers, for the small-mesh path (issue 21: a 115-face
disk's whole unwrap is ~0.5 ms, and numpy's wrappers cost 1-4 us a call): ``quiet`` for
``np.errstate(kind="ignore")``, ``einsum`` for ``np.einsum`` without ``optimize``. The same
numbers and the same error modes as the calls they stand for (``tests/core/test_quiet.py``)."""
import numpy as np

# numpy 1.x keeps each thread's floating-point error modes as a list [bufsize, mask, call]
# (``np.geterrobj``), the mode of each kind (3 bits) at these shifts; "ignore" is 0.
_SHIFTS = {"divide": 0, "over": 3, "under": 6, "invalid": 9}


class _Quiet:
    """``np.errstate(**{kind: "ignore" for kind in kinds})`` on numpy 1.x, the thread's error
    object set straight: ~0.5 us a block against errstate's ~2-4 us (``seterr`` and ``geterr``
    in Python), a few blocks on every call of a small mesh's path. The other kinds' modes and
    the error callback are kept, and the old object is restored on leaving."""
    __slots__ = ("_clear", "_old")

    def __init__(self, kinds):
        self._clear = ~sum(7 << _SHIFTS[k] for k in kinds)

    def __enter__(self):
        old = self._old = np.geterrobj()
        np.seterrobj([old[0], old[1] & self._clear, old[2]])

    def __exit__(self, *exc):
        np.seterrobj(self._old)


def quiet(*kinds):
    """A context in which the floating-point errors of ``kinds`` ("divide", "over", "under",
    "invalid") are ignored: ``np.errstate`` with those set to "ignore" (its own on numpy 2, where
    it is cheap and the error object is gone)."""
    if _FAST:
        return _Quiet(kinds)
    return np.errstate(**dict.fromkeys(kinds, "ignore"))


_FAST = hasattr(np, "geterrobj") and hasattr(np, "seterrobj")

# ``np.einsum`` without its Python wrapper (~1.5 us a call): with no ``optimize`` it hands its
# operands to this very function.
try:
    from numpy._core.multiarray import c_einsum as einsum
except ImportError:
    try:
        from numpy.core.multiarray import c_einsum as einsum
    except ImportError:                 # pragma: no cover - a numpy without it
        einsum = np.einsum
