"""Fuzzing the atlas packer's contract (issue 22): ``pack_islands`` on random island sets.

Sets of 1 to 200 islands (boxes, slivers 40 to 400 times longer than wide, islands with a hole,
huge and tiny islands together, a few islands among many tiny ones packed with the product's
default search, a zero-area island in UV or in 3D), paddings of 0 to 64 texels at
resolutions 64 to 16384, turns none | 90 | any; fitted to the square, at a fixed texel density
(with or without UDIM spill), or around pinned islands (some put outside the square). For every
example: nothing escapes but a typed ``bd_uv.BDError`` whose message is one line in the user's
terms (and inputs that cannot be packed must raise it); the inputs are byte-identical afterwards;
every returned layout is certified by ``packing_checks.check_layout``, code that shares nothing
with the packer (every corner inside its tile, exact triangle overlap test, brute-force gaps at
least the padding, one texel density, pinned islands bit for bit, no mirror).

Each example is cheap: spyrrow's constructive placement only (``solve_seconds=0``) for most
draws, 0.2 s of search and compaction for one in four, a one-second search for one in twenty;
one solve for most draws, the product's two rounds for one in five, two rounds of two solves at
once (threads) for one in five; 200 islands at most in the main test, and 1,000 to 5,000 in one
example per thousand of the depth (``test_thousands_of_islands_...``: minutes each, so deep runs
only).

CI-friendly: 10 examples; ``BD_UV_FUZZ_EXAMPLES=2000`` (or ``bash scripts/fuzz_deep.sh``) runs
deeper.
"""
import os

import numpy as np
import pytest
from hypothesis import HealthCheck, event, example, given, settings
from hypothesis import strategies as st

from bd_uv.errors import BDError
from bd_uv.packing import PackOptions, pack_islands
from packing_checks import check_layout
from packing_sets import RECT, annulus

EXAMPLES = int(os.environ.get("BD_UV_FUZZ_EXAMPLES", "10"))
KINDS = ("box", "sliver", "hole")


def island_set(k, seed, kinds, huge_tiny, zero, tiny_after=0):
    """k islands of the given kinds; each a template stretched, its 3D copy scaled (densities
    differ before packing), its UVs turned and moved anywhere (never mirrored).

    huge_tiny : island 0 huge (20 x 14), the others 50 times smaller
    tiny_after : when > 0, the islands from this one on at most 0.02 long (packing.tiny's case:
        a few charts and many tiny ones, as a model's bolts)
    zero : None | "uv" | "3d": the last island's UVs (or 3D corners) collapsed onto a segment

    Returns V (n,3), F (m,3), corner_uv (m,3,2), face_island (m,)
    """
    rng = np.random.default_rng(seed)
    Vs, Fs, uvs, labs, n = [], [], [], [], 0
    for i in range(k):  # per island (test data)
        kind = kinds[rng.integers(len(kinds))]
        P, T = annulus(rng.uniform(0.1, 0.45)) if kind == "hole" else RECT
        size = rng.uniform(0.2, 1.0, 2)
        if kind == "sliver":
            size[0] *= rng.uniform(40, 400)
        if huge_tiny:
            size = np.array([20.0, 14.0]) if i == 0 else size * 0.02
        elif tiny_after and i >= tiny_after:     # at most 0.02 long (slivers too)
            size = size / size.max() * rng.uniform(0.004, 0.02)
        local = P * size
        V = np.c_[local * rng.uniform(0.5, 2.0), np.zeros(len(P))]
        th = rng.uniform(0, 2 * np.pi)
        R = np.array([[np.cos(th), -np.sin(th)], [np.sin(th), np.cos(th)]])
        uv = local @ R.T * rng.uniform(0.1, 3.0) + rng.uniform(-5, 5, 2)
        if zero and i == k - 1:
            if zero == "uv":
                uv = np.c_[uv[:, 0], np.zeros(len(uv))]
            else:
                V[:, 1] = 0.0
        Vs.append(V)
        Fs.append(T + n)
        uvs.append(uv[T])
        labs.append(np.full(len(T), i))
        n += len(P)
    return np.concatenate(Vs), np.concatenate(Fs), np.concatenate(uvs), np.concatenate(labs)


def pin_into_cells(uv, lab, which, margin, outside):
    """Put the islands ``which`` into cells of a 3 x 3 grid of the unit square, ``margin`` inside
    each cell (so pinned islands keep the padding to each other and to the square's edge); with
    ``outside``, the first of them is moved past the square's right edge instead."""
    uv = uv.copy()
    cell = 1.0 / 3
    for c, i in enumerate(which):  # per pinned island (test data)
        P = uv[lab == i]
        lo, hi = P.reshape(-1, 2).min(0), P.reshape(-1, 2).max(0)
        at = np.array([c % 3, c // 3]) * cell + margin
        uv[lab == i] = (P - lo) * ((cell - 2 * margin) / (hi - lo).max()) + at
    if outside:
        uv[lab == which[0]] += [1.0, 0.0]
    return uv


@st.composite
def problems(draw):
    many = draw(st.sampled_from([False] * 5 + [True]))
    k = draw(st.integers(40, 200) if many else st.integers(1, 30))
    kinds = draw(st.lists(st.sampled_from(KINDS), min_size=1, max_size=3, unique=True))
    huge_tiny = draw(st.booleans())
    zero = draw(st.sampled_from([None] * 8 + ["uv", "3d"]))
    seed = draw(st.integers(0, 2 ** 32 - 1))
    res = draw(st.sampled_from([64, 128, 256, 512, 1024, 2048, 4096, 8192, 16384])
               | st.integers(64, 16384))
    pad = draw(st.sampled_from([0.0, 1.0, 4.0, 64.0]) | st.floats(0.0, 64.0))
    pad = min(pad, res / 8)          # larger is refused by PackOptions (its own test)
    rotate = draw(st.sampled_from(["any", "90", "none"]))
    mode = draw(st.sampled_from(["fit", "fit", "density", "udim", "pinned"]))
    # 0: the nesting's first placement only; 0.2: with a little search and compaction (half of
    # the time, .compact's linear programs, each step checked by GEOS); 1: a longer search
    solve_seconds = draw(st.sampled_from([0] * 14 + [0.2] * 5 + [1]))
    solves = draw(st.sampled_from([1, 1, 1, 2, 4]))   # 2: the product's two rounds; 4: threads
    fill = draw(st.floats(0.05, 4.0))            # 3D area at the density over a tile's area
    n_pins = draw(st.integers(1, 9))
    outside = draw(st.sampled_from([False] * 4 + [True]))
    fits = draw(st.sampled_from([False, True, True, True]))
    # a few charts and many tiny ones (packing.tiny): the product's default search, as its
    # gate asks (the tiny ones dropped into the room the others leave)
    tiny_after = draw(st.sampled_from([0] * 8 + [2, 3, 6]))
    if tiny_after:
        k = draw(st.integers(5 * tiny_after, 200))
        huge_tiny, mode, solve_seconds, solves = False, "fit", None, 1
    return dict(tiny_after=tiny_after, fits=fits, k=k, kinds=kinds, huge_tiny=huge_tiny,
                zero=zero, seed=seed, res=res, pad=pad,
                rotate=rotate, mode=mode, solve_seconds=solve_seconds, fill=fill, n_pins=n_pins,
                outside=outside, solves=solves)


def _pack(p):
    """The inputs and options of a drawn problem, and what the contract expects of them."""
    V, F, uv, lab = island_set(p["k"], p["seed"], p["kinds"], p["huge_tiny"], p["zero"],
                               p.get("tiny_after", 0))
    k, res, pad = p["k"], p["res"], p["pad"]
    kw = dict(resolution=res, padding_px=pad, rotate=p["rotate"], solves=p.get("solves", 1),
              solve_seconds=p["solve_seconds"], seed=p["seed"] % 1000)
    pinned = None
    if p["mode"] in ("density", "udim"):
        P3 = V[F]
        a3 = 0.5 * np.linalg.norm(np.cross(P3[:, 1] - P3[:, 0], P3[:, 2] - P3[:, 0]), axis=1).sum()
        density = res * float(np.sqrt(p["fill"] / max(a3, 1e-300)))
        if p.get("fits", False):
            # at most the density at which the largest island's 3D bounding box diagonal fits a
            # tile with the padding (else most such draws are refusals: "larger than a tile")
            diag = max(float(np.linalg.norm(np.ptp(V[np.unique(F[lab == i])], axis=0)))
                       for i in range(k))
            density = min(density, 0.9 * (res - 2 * pad) / max(diag, 1e-300))
        kw.update(texel_density=density, udim=p["mode"] == "udim")
    margin = 0.5 * pad / res + 1e-3
    if p["mode"] == "pinned" and k > 1 and 1.0 / 3 - 2 * margin > 0.02:
        which = np.random.default_rng(p["seed"]).choice(k, min(p["n_pins"], k - 1), replace=False)
        uv = pin_into_cells(uv, lab, which, margin, p["outside"])
        pinned = np.zeros(k, bool)
        pinned[which] = True
    return V, F, uv, lab, PackOptions(**kw), pinned


def problem(**kw):
    """A drawn problem written out (regression tests): the simplest draw, changed by ``kw``."""
    p = dict(k=1, kinds=["box"], huge_tiny=False, zero=None, seed=0, res=64, pad=0.0,
             rotate="any", mode="fit", solve_seconds=0, fill=1.0, n_pins=1, outside=False)
    p.update(kw)
    return p


# Found by this contract: two slivers whose outlines' total area was below the strip's height
# times the padding; spyrrow starts from a strip that narrow and panicked ("Offset resulted in an
# empty polygon"), reported as "the nesting failed". Fixed in bd_uv.packing.nest._nest_grown.
THIN_SLIVERS = problem(k=2, kinds=["sliver"], pad=1.0)


def test_two_slivers_thinner_than_the_padding_are_packed():
    V, F, uv, lab, options, _ = _pack(THIN_SLIVERS)
    packed = pack_islands(V, F, uv, lab, options)
    check_layout(V, F, uv, lab, packed, options)


# Found by this contract: an island whose hole has more area than the island itself (a frame);
# its outline was taken as the polygon of most area among the boundary's faces, i.e. the hole,
# so the nesting packed the hole's outline and islands overlapped (uncertified layout returned).
# Fixed in bd_uv.packing.outlines.chart_outlines: the outer ring is the one enclosing the most.
WIDE_HOLE = problem(k=3, kinds=["box", "hole"], seed=17, pad=4.0)


def test_an_island_whose_hole_outweighs_it_is_nested_by_its_outer_ring():
    V, F, uv, lab, options, _ = _pack(WIDE_HOLE)
    holes = [i for i in range(3) if (lab == i).sum() == 8]
    assert holes                                   # the set has a frame with a wide hole
    packed = pack_islands(V, F, uv, lab, options)
    check_layout(V, F, uv, lab, packed, options)


# Found by this contract (about 1 % of draws): spyrrow gave up on a chart allowed no turn (or
# quarter turns only) when the strip left it under about 1 % of its height to spare, panicking
# "strip-width is running away ..., item 1 does not seem to fit into the strip", reported as "the
# nesting failed". The least square side left out that spyrrow keeps the separation (the padding
# of a HEADROOM larger square) to both edges of the strip. Fixed in
# bd_uv.packing.square.square_layout: the least side keeps the widest chart that separation from
# both edges with 3 % to spare for fixed turns (FIT), a refusal is retried in a larger strip, and
# a strip with no square in it leads to the square strip of the density it reached.
SLIVERS_NO_TURN = problem(k=19, kinds=["sliver"], seed=3948950062, res=179, pad=22.375,
                          rotate="none")
HUGE_TINY_NO_TURN = problem(k=29, kinds=["box", "sliver", "hole"], huge_tiny=True,
                            seed=2775566334, res=128, pad=4.0, rotate="none")
MIXED_WIDE_PADDING = problem(k=3, kinds=["hole", "box", "sliver"], seed=2413189317, res=128,
                             pad=16.0, rotate="none")
HOLES_QUARTER_TURNS = problem(k=13, kinds=["hole"], seed=2030437107, res=403, pad=50.375,
                              rotate="90")


@pytest.mark.parametrize("p", [SLIVERS_NO_TURN, HUGE_TINY_NO_TURN, MIXED_WIDE_PADDING,
                               HOLES_QUARTER_TURNS])
def test_charts_with_fixed_turns_and_wide_padding_are_packed(p):
    V, F, uv, lab, options, _ = _pack(p)
    packed = pack_islands(V, F, uv, lab, options)
    check_layout(V, F, uv, lab, packed, options)


# Found by this contract (seed 4, 100 examples): 189 huge and tiny islands spilled over 14 UDIM
# tiles at 128 px; stored as float32, a chart 4e-4 wide in tile 1010 (u near 10, float32 spacing
# about 1e-6) read its density 0.1 % off, and the contract asserted the certificate's density
# spread within 1e-3 of 1 while its own per-chart bound allows 1e-3 + 1e-6 / width. Not a packer
# fault (the spread is exactly 1 before storing); the contract now compares the certificate's
# spread with the spread it recomputes from the stored UVs (packing_checks.check_layout).
FAR_TILES_TINY_CHARTS = problem(k=120, kinds=["box", "sliver"], huge_tiny=True, seed=14534,
                                res=128, pad=16.0, rotate="90", mode="udim", fill=0.3)


def test_tiny_charts_in_far_tiles_keep_their_density_as_stored():
    V, F, uv, lab, options, _ = _pack(FAR_TILES_TINY_CHARTS)
    packed = pack_islands(V, F, uv, lab, options)
    tiles = tuple(range(1001, int(packed.tile.max()) + 1))
    cert = check_layout(V, F, uv, lab, packed, options, tiles=tiles)
    assert len(tiles) >= 9 and cert.density_spread > 1.001     # float32 in far tiles


# Found by this contract (2,000 deep, seed 515151, after 386 examples): two boxes spilled into
# UDIM tiles 1001 and 1002 at no padding; the contract measured the gap across the tiles' border
# (11.5 px) where the certificate, rightly, measures gaps within each tile only (each tile is its
# own texture) and found none: the contract's check now measures within each tile too.
TWO_TILES_NO_PADDING = problem(k=2, seed=32, mode="udim", fill=1.0)

# Found by this contract (2,000 deep, seed 515151, after 1,128 examples), in the contract's own
# check: with long edges cut into pieces (for 5,000 islands) the contract's least gap is exact
# only up to its reach (twice the padding); around pinned charts the least gap was larger, the
# contract's figure an upper bound, and it asserted equality with the certificate's exact one.
PINNED_WIDE_GAPS = problem(k=40, kinds=["box", "sliver"], seed=77118, res=4096,
                           pad=2.93054006979004, mode="pinned", fill=2.93054006979004, n_pins=8)

# Found by this contract (2,000 deep, seed 31415926, after 1,334 examples), two at once:
# - spyrrow panicked ("Offset resulted in an empty polygon") on 93 boxes and slivers at 64 px
#   with no padding, their area a hair above the reach of the old nest.NARROW, and the PackError
#   carried Rust's whole backtrace, many lines; they are now nested grown (as every outline
#   is: spyrrow is given no separation of its own);
# - the contract's own bound on float32's change of a chart's density used the chart's box, not
#   its thinnest triangle: a sliver 4e-5 high in tile 1006 moved 1.8e-3 (bound now 2.3e-2).
SLIVERS_EMPTY_OFFSET = problem(k=93, kinds=["box", "sliver"], huge_tiny=True, res=64, pad=0.0,
                               rotate="none", mode="udim", solve_seconds=0, fill=0.05)
FAR_TILE_SLIVER = problem(k=91, kinds=["box", "sliver"], huge_tiny=True, res=64, pad=8.0,
                          rotate="90", mode="udim", solve_seconds=0, fill=0.125)


# packing.tiny's case (most charts tiny, a few others: the others packed alone, the tiny ones
# dropped into the room they leave), with holes and slivers among the tiny ones.
TINY_AMONG_FEW = problem(k=60, kinds=["box", "hole", "sliver"], tiny_after=3, seed=11, res=1024,
                         pad=4.0, solve_seconds=None)


# 119 slivers at 64 px (seed 7373 at 300 deep): one face of a sliver, 3e-8 across once packed,
# is thinner than float32's step where it lies and collapses as stored. No similarity can keep
# it: the layout certificate now counts faces flipped or collapsed as stored and says so.
SLIVER_GONE_IN_FLOAT32 = dict(
    tiny_after=2, fits=False, k=119, kinds=["sliver"], huge_tiny=False, zero=None, seed=1,
    res=64, pad=4.0, rotate="none", mode="fit", solve_seconds=None, fill=1.0, n_pins=1,
    outside=False, solves=1)


@settings(max_examples=EXAMPLES, deadline=None,
          suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large])
@given(p=problems())
@example(p=SLIVER_GONE_IN_FLOAT32)
@example(p=TINY_AMONG_FEW)
@example(p=dict(TINY_AMONG_FEW, rotate="none", pad=16.0, res=256))
@example(p=TWO_TILES_NO_PADDING)
@example(p=PINNED_WIDE_GAPS)
@example(p=SLIVERS_EMPTY_OFFSET)
@example(p=FAR_TILE_SLIVER)
@example(p=THIN_SLIVERS)
@example(p=WIDE_HOLE)
@example(p=SLIVERS_NO_TURN)
@example(p=HUGE_TINY_NO_TURN)
def test_every_packed_layout_is_certified_or_a_typed_error(p):
    V, F, uv, lab, options, pinned = _pack(p)
    inputs = [V, F, uv, lab] + ([pinned] if pinned is not None else [])
    before = [(a.dtype, a.shape, a.tobytes()) for a in inputs]
    # a zero-area island that moves, or a pinned island outside the square, must be refused (a
    # pinned zero-area island stays as the user left it)
    doomed = (p["zero"] is not None and (pinned is None or not pinned[-1])) \
        or (pinned is not None and p["outside"])
    try:
        packed = pack_islands(V, F, uv, lab, options, pinned=pinned)
    except BDError as err:
        msg = str(err)
        event(f"{p['mode']}: refused ({type(err).__name__}: {msg.split(':')[0][:40]})")
        assert msg and "\n" not in msg and "Traceback" not in msg, msg
    else:
        assert not doomed, "a zero-area island or a pinned island outside the square was packed"
        tiles = (1001,)
        if options.udim:
            tiles = tuple(range(1001, int(packed.tile.max()) + 1))
        check_layout(V, F, uv, lab, packed, options, tiles=tiles, pinned=pinned)
        event(f"{p['mode']}: certified" + (f", {len(tiles)} tiles" if options.udim else "")
              + (", a few islands among tiny ones" if p.get("tiny_after") else ""))
    assert [(a.dtype, a.shape, a.tobytes()) for a in inputs] == before, "an input was changed"


@st.composite
def crowds(draw):
    """1,000 to 5,000 islands (the issue's upper end), constructive placement only."""
    p = draw(problems())
    p.update(k=draw(st.integers(1000, 5000)), solve_seconds=0, solves=1,
             mode=draw(st.sampled_from(["fit", "density", "udim"])))
    return p


# One example in a thousand of the contract's depth (none in CI): 5,000 boxes take about 3 min to
# pack and 1.5 min to check on the shared machine (load 7).
CROWD_EXAMPLES = EXAMPLES // 1000


@pytest.mark.skipif(CROWD_EXAMPLES < 1, reason="thousands of islands: deep runs only "
                    "(BD_UV_FUZZ_EXAMPLES >= 1000, scripts/fuzz_deep.sh)")
@settings(max_examples=max(CROWD_EXAMPLES, 1), deadline=None,
          suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large])
@given(p=crowds())
def test_thousands_of_islands_are_certified_or_a_typed_error(p):
    test_every_packed_layout_is_certified_or_a_typed_error.hypothesis.inner_test(p=p)
