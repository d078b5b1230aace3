"""UnwrapOptions: the one place an unwrap option is defined and checked (issue 20, item 5)."""
import dataclasses
import json
import pickle

import numpy as np
import pytest

import bd_uv
from bd_uv import OptionError, UnwrapOptions
from bd_uv.arguments import unwrap_options_of
from bd_uv.batch import JobOptions
from bd_uv.cli import build_parser
from bd_uv.options import ENTRY_SEAMS_MODE
from bd_uv.scheduling import options_sha256
from helpers import reference_distortion


def bumpy_grid(n=6):
    xs, ys = np.meshgrid(np.linspace(0, 1, n + 1), np.linspace(0, 1, n + 1))
    x, y = xs.ravel(), ys.ravel()
    V = np.stack([x, y, 0.4 * np.sin(3 * x) * np.cos(2 * y)], axis=1)
    i, j = np.meshgrid(np.arange(n), np.arange(n))
    a = (j * (n + 1) + i).ravel()
    b, c, d = a + 1, a + n + 2, a + n + 1
    F = np.stack([np.stack([a, b, c], 1), np.stack([a, c, d], 1)], 1).reshape(-1, 3)
    return V, F.astype(np.int64)


def test_defaults_are_todays():
    o = UnwrapOptions()
    assert (o.seams_mode, o.method, o.bound, o.frames, o.raise_bound, o.bound_limit, o.cone,
            o.time_budget, o.stretch, o.boundary, o.overlap) == \
        ("marked", "lscm", 5.0, "auto", True, 1000.0, "soc", None, None, "free", "cut")
    assert o.seams_stretch == 2.0 and UnwrapOptions(stretch=3.0).seams_stretch == 3.0


@pytest.mark.parametrize("values, option", [
    (dict(method="lsqm"), "method"),
    (dict(bound=0.5), "bound"),
    (dict(bound=float("nan")), "bound"),
    (dict(bound="minimise"), "bound"),
    (dict(frames="uv"), "frames"),
    (dict(raise_bound="yes"), "raise_bound"),
    (dict(bound_limit=float("inf")), "bound_limit"),
    (dict(cone="psd"), "cone"),
    (dict(time_budget=-1.0), "time_budget"),
    (dict(stretch=0.5), "stretch"),
    (dict(bound=3.0, stretch=1.2), "stretch"),          # S^2 < C
    (dict(boundary="square"), "boundary"),
    (dict(overlap="keep"), "overlap"),
    (dict(boundary="circle", bound="auto"), "boundary"),
    (dict(boundary="circle", frames="conformal"), "boundary"),
    (dict(seams_mode="auto", bound="auto"), "seams_mode"),
    (dict(seams_mode="auto", boundary="circle"), "seams_mode"),
    (dict(seams_mode="auto", frames="input-uv"), "seams_mode"),
    (dict(seams_mode="auto", stretch=0.5), "stretch"),
    (dict(seams_mode=True), "seams_mode"),
    (dict(seams_mode="everywhere"), "seams_mode"),
])
def test_a_bad_option_is_named(values, option):
    with pytest.raises(OptionError) as info:
        UnwrapOptions(**values)
    assert info.value.option == option
    assert isinstance(info.value, bd_uv.BDError) and isinstance(info.value, ValueError)
    assert option.split("_")[0] in str(info.value)


def test_frozen_and_pickled_as_they_are():
    o = UnwrapOptions(method="arap", bound=3.0, stretch=2.0)
    with pytest.raises(dataclasses.FrozenInstanceError):
        o.bound = 4.0
    assert pickle.loads(pickle.dumps(o)) == o
    job = JobOptions(o, pack=True, cut=True, margin=0.01)
    assert pickle.loads(pickle.dumps(job)) == job
    assert json.loads(json.dumps(job.as_dict()))["bound"] == 3.0
    with pytest.raises(OptionError):
        o.replace(bound=5.0)          # replace checks again: S = 2 < sqrt(5)
    assert UnwrapOptions(seams_mode="auto").seams_stretch == 2.0   # the seam search's S: any >= 1


def test_keywords_and_the_object_unwrap_alike():
    V, F = bumpy_grid()
    by_keywords = bd_uv.unwrap(V, F, bound=1.5, method="arap")
    by_object = bd_uv.unwrap(V, F, options=UnwrapOptions(bound=1.5, method="arap"))
    np.testing.assert_array_equal(by_keywords.corner_uv, by_object.corner_uv)
    D, flipped = reference_distortion(V, F, by_object.corner_uv)
    assert not flipped.any() and D.max() <= by_object.islands[0].bound_certified * (1 + 1e-9)
    # keywords replace the object's fields
    over = bd_uv.unwrap(V, F, options=UnwrapOptions(bound=4.0, method="arap"), bound=1.5)
    np.testing.assert_array_equal(over.corner_uv, by_object.corner_uv)
    with pytest.raises(OptionError, match="'bund' is not an unwrap option"):
        bd_uv.unwrap(V, F, bund=2.0)


def test_the_command_line_defaults_are_the_options_defaults():
    for command in (["unwrap", "x.obj", "-o", "y.obj"], ["batch", "x", "-o", "y"]):
        # The entry points start in ENTRY_SEAMS_MODE ("needed"); every other default is the
        # options' own.
        assert unwrap_options_of(build_parser().parse_args(command)) == \
            UnwrapOptions(seams_mode=ENTRY_SEAMS_MODE)
    args = build_parser().parse_args(["unwrap", "x.obj", "-o", "y.obj", "--seams", "auto",
                                      "--bound", "2", "--no-raise", "--overlap", "fail"])
    assert unwrap_options_of(args) == UnwrapOptions(seams_mode="auto", bound=2.0,
                                                    raise_bound=False, overlap="fail")
    args = build_parser().parse_args(["batch", "x", "-o", "y", "--bound", "auto"])
    assert unwrap_options_of(args).time_budget == 120.0     # the command line's budget


def test_the_journal_hash_follows_the_options():
    a = JobOptions(UnwrapOptions(bound=3.0), pack=True, cut=True)
    assert options_sha256(a, None) == options_sha256(pickle.loads(pickle.dumps(a)), None)
    assert options_sha256(a, None) != options_sha256(
        JobOptions(UnwrapOptions(bound=3.5), pack=True, cut=True), None)
    assert options_sha256(a, None) != options_sha256(a, "auto")


def test_job_options_of_a_dict_keeps_the_old_meaning():
    """A dict of unwrap keywords (no layout keys) neither packs nor cuts in the layout; ``cut``
    decides ``overlap``."""
    assert JobOptions.of({"bound": 3.0}) == JobOptions(UnwrapOptions(bound=3.0))
    assert JobOptions.of({"bound": 3.0, "cut": False, "pack": True}) == JobOptions(
        UnwrapOptions(bound=3.0, overlap="fail"), pack=True, cut=False)


def test_options_made_from_plain_values_are_kept_and_still_checked():
    """``unwrap_options`` keeps what it made of plain values (frozen, so one object serves every
    call): the same options as made afresh; a value equal to a kept one but of another type is
    checked on its own (True == 1.0, and True is no bound); refused values stay refused."""
    from bd_uv.options import _MADE, unwrap_options
    _MADE.clear()
    a = unwrap_options(None, bound=5.0, method="lscm")
    assert unwrap_options(None, bound=5.0, method="lscm") is a
    assert a == UnwrapOptions(bound=5.0, method="lscm")
    assert unwrap_options(None, bound="auto") == UnwrapOptions(bound="auto")
    one = unwrap_options(None, bound=1.0)
    assert one.bound == 1.0
    for _ in range(2):
        with pytest.raises(OptionError):
            unwrap_options(None, bound=True)
        with pytest.raises(OptionError):
            unwrap_options(None, bound=0.5)
        with pytest.raises(OptionError):
            unwrap_options(None, bound=float("nan"))
    assert unwrap_options(None, bound=1) == UnwrapOptions(bound=1)
    # a value that is not plain (a numpy float) is checked and made every time, not kept
    b = unwrap_options(None, bound=np.float64(3.0))
    assert b == UnwrapOptions(bound=3.0) and b is not unwrap_options(None, bound=np.float64(3.0))
    # the store stays small
    for k in range(200):
        unwrap_options(None, bound=1.0 + k)
    assert len(_MADE) <= 64
