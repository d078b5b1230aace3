"""``array_calls.quiet``: the small path's ``np.errstate(kind="ignore", ...)`` without its Python
``seterr``/``geterr``: the same modes inside (the kinds named ignored, the others as they were),
the modes before restored on leaving (also after an error), per thread as numpy keeps them."""
import itertools
import threading
import warnings

import numpy as np
import pytest

from bd_uv.array_calls import quiet

KINDS = ("divide", "over", "under", "invalid")


def _ops():
    with np.errstate(all="ignore"):
        big = np.array([1e308])
    return {"divide": lambda: np.array([1.0]) / np.array([0.0]),
            "over": lambda: big * 10.0,
            "under": lambda: np.array([1e-308]) * 1e-308,
            "invalid": lambda: np.array([0.0]) / np.array([0.0])}


@pytest.mark.parametrize("outer", ["warn", "raise", "ignore", "print"])
def test_the_modes_inside_and_after_are_errstates(outer):
    ops = _ops()
    for r in range(1, 5):
        for kinds in itertools.combinations(KINDS, r):
            with np.errstate(all=outer, under="warn"):
                before = np.geterr()
                with np.errstate(**dict.fromkeys(kinds, "ignore")):
                    want = np.geterr()
                with quiet(*kinds):
                    got = np.geterr()
                    for k in kinds:          # the kinds named pass silently
                        with warnings.catch_warnings():
                            warnings.simplefilter("error")
                            ops[k]()
                assert got == want
                assert np.geterr() == before


def test_the_modes_are_restored_after_an_error_and_when_nested():
    with np.errstate(all="raise"):
        before = np.geterr()
        with pytest.raises(FloatingPointError):
            with quiet("invalid"):
                assert np.geterr()["invalid"] == "ignore"
                with quiet("divide"):
                    assert np.geterr()["divide"] == "ignore"
                    assert np.geterr()["invalid"] == "ignore"
                assert np.geterr()["divide"] == "raise"
                _ops()["divide"]()
        assert np.geterr() == before


def test_each_thread_keeps_its_own_modes():
    seen = {}
    inside, done = threading.Event(), threading.Event()

    def other():
        with np.errstate(divide="raise"):
            inside.wait()
            seen["other"] = np.geterr()["divide"]
        done.set()
    t = threading.Thread(target=other)
    t.start()
    with np.errstate(divide="warn"):
        with quiet("divide"):
            inside.set()
            done.wait()
            seen["here"] = np.geterr()["divide"]
    t.join()
    assert seen == {"other": "raise", "here": "ignore"}


def test_without_numpys_error_object_it_is_errstate(monkeypatch):
    """numpy 2 has no ``geterrobj``: ``quiet`` is ``np.errstate`` itself there."""
    from bd_uv import array_calls
    monkeypatch.setattr(array_calls, "_FAST", False)
    q = quiet("invalid", "divide")
    assert isinstance(q, np.errstate)
    with np.errstate(all="raise"):
        with q:
            assert np.geterr() == {"divide": "ignore", "over": "raise", "under": "raise",
                                   "invalid": "ignore"}
        assert np.geterr()["invalid"] == "raise"
