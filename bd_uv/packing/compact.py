"""Compaction: a square layout made smaller by small moves of every chart at once.

spyrrow's layouts keep slack: its separation is the padding of a square ``HEADROOM`` larger than
the one found (measured least gaps 4.4-4.6 px for 4 px), and within its short search it leaves
loose space between charts. A sequence of linear programs (Li and Milenkovic's compaction, 1995)
removes it: each step moves every chart by at most ``step`` (a translation, and with any turn
allowed a small turn about its centre), minimising the square's side S subject to

- every outline inside [e, S - e]^2 with e = S padding / 2 + tol (its vertices near its extremes);
- every vertex v of a chart at least padding S + 2 tol from the nearest point c of every segment
  of another chart within reach (``u . (v' - c') >= sep`` along u = (v - c) / |v - c|: exact for
  a translation when c is inside the segment, a tangent of the circle round c otherwise).

Each step's layout is checked exactly (GEOS distances between the moved outlines, every point
inside) before it is kept: else half and a quarter of the move are tried (the linear model holds
on the segment to the move), then a shorter step. Turns are linearised; their second-order error
(r phi^2) and the tilt of a turning segment's line (the points' slide times phi) are kept as
slack in the rows. The charts keep their shape: a turn and a translation each, never a mirror.
One step's linear program is :mod:`.compact_step`.

Measured (load ~10-13, from the two-round nesting's layouts): cow 0.629 -> 0.709, camel
0.632 -> 0.693, suzanne 0.559 -> 0.611 in 40 programs (2.0, 1.9, 0.6 s of CPU); see
docs/ARCHITECTURE.md.
"""
import time

import numpy as np

from .nest import Placement, rotations
from .refit import anchored, fits
from .compact_step import close, step_lp
from .relocate import relocate

STEP = 0.005      # largest move of a point in one step, as a fraction of the square's side
MARGIN = 1e-5     # separation kept above the padding, as a fraction of the side (0.01 px at 1024)
LINE_SEARCH = (1.0, 0.5, 0.25)  # fractions of a step's move tried in turn
REL_GAIN = 1e-5   # a program shrinking the side by less than this fraction: a shorter step
LEAST_STEP = 1e-4  # the compaction ends when the step falls below this fraction of the side
NEAR_LEAST = 1e-3  # ... or when the side is within this fraction of the least one conceivable
# ... or when the side shrank by less than STALL_GAIN over the last STALL_SHARE of the budget
# (measured from nested layouts of suzanne, cow, camel, dino, seeds 0-2: past that point the
# rest of the budget gained 0-0.1 % of coverage on suzanne and cow)
STALL_SHARE = 0.25
STALL_GAIN = 5e-4
# at half the budget (or when the side stalls or converges before it) the small charts that
# bound the square are moved into the free space deepest inside it (.relocate) and the
# compaction goes on; measured from the same nested layouts and the same CPU budget (seeds
# 0-3, load 4-5): cow 0.6963 -> 0.7026 mean, suzanne 0.5945 -> 0.6007, camel 0.6910 ->
# 0.6959, dino 0.6730 -> 0.6773, eight 0.5861 -> 0.5862; only when the side stalled: cow 0.7008,
# the others unchanged (it rarely stalls); at 0.35, 0.4, 0.65 of the budget: within 0.5 % of
# 0.5 but camel lower
RELOCATE_AT = 0.5
MOVE_ROUNDS = 4   # at most this many rounds of moves
# The budget is where a compaction is expected to have converged, not where every one has: one
# still shrinking at its end (by STALL_GAIN or more over the last STALL_SHARE of the budget, the
# stall rule's own measure) goes on while it does, up to EXTEND times the budget; one converged
# or stalled before it ends as before. Measured on pack27's 23 dumped compactions of 8 meshes
# (issue18-pack28-2026-11-29.md, CPU, 3 runs each): at 2x, dino +0.9-1.5 % of area, max3ds
# +1.8-1.9 %, Wuson.off +1.1 %, cow +0.45 %, igl-elephant +0.4 % on one of 3, igl-arm, homer
# and rocker-arm unchanged (stopped gaining by half their budgets), geometric mean +0.46 %; 1.5x
# gives about two thirds of that for half the added CPU (dino +0.4-0.6 s, Wuson.off +0.4 s: its
# 2.15 s pack, 0.14x Blender's time, stays under 0.2x where 2x would come to ~0.19x)
EXTEND = 1.5


def _rings(outlines):
    """Per point: owner chart, and index of the next point of its ring."""
    sizes = np.array([len(o) for o in outlines])
    owner = np.repeat(np.arange(len(outlines)), sizes)
    starts = np.r_[0, np.cumsum(sizes)[:-1]]
    nxt = np.arange(len(owner)) + 1
    nxt[starts + sizes - 1] = starts
    return owner, nxt


def _placed(outlines, angle, shift):
    """(n,2) every outline point turned by its chart's angle (degrees) and moved by its shift."""
    R = rotations(angle)
    return np.concatenate([o @ R[i].T + shift[i] for i, o in enumerate(outlines)])


def compact_square(outlines, placement, side, options, tol, seconds, max_programs=None,
                   least_side=0.0, clock=time.process_time, cancel=None):
    """Shrink a square layout by compaction steps for ``seconds``, or past them while the side
    still shrinks by ``STALL_GAIN`` over the last ``STALL_SHARE`` of them, up to ``EXTEND``
    times (or until the step falls below ``LEAST_STEP`` of the side: no program gains, or no
    move passes the check; or until the side is within ``NEAR_LEAST`` of ``least_side``; or
    until it stalls). In a run bounded by time, at
    ``RELOCATE_AT`` of it (or at a stall or convergence before, and at later ones) the small
    charts against the square's edges are moved into the free space deepest inside it
    (:func:`.relocate.relocate`, checked exactly) and the steps go on from there.

    Parameters
    ----------
    outlines : list of (n_i,2) float arrays, centred outlines
    placement : Placement in the square [0, side]^2 with the padding kept
    side : float
    options : PackOptions (padding; rotate "any": small turns too)
    tol : float, outline simplification tolerance
    seconds : float, CPU time of this process to take (up to ``EXTEND`` times as much while
        the side still shrinks): on a loaded machine the compaction takes longer but reaches
        as far (a program's solve is cut at the time left, by its own
        clock; its exact checks are finished)
    max_programs : int, optional: at most this many linear programs (deterministic runs)
    least_side : float, a side no layout reaches (the largest chart's least square with the
        padding): nothing is left to gain near it (fandisk's 3 charts start there)
    clock : the CPU clock of ``seconds`` (``time.thread_time`` for a compaction on a thread of
        its own beside the nesting: :mod:`.ahead`)
    cancel : threading.Event, optional: once set, the compaction ends at its next program (its
        layout is then of no use to the caller)

    Returns
    -------
    Placement, side (no larger than given), steps taken
    """
    # imported before the clock starts: inside the first compaction, scipy.optimize took 0.2 s
    # of its CPU budget (0.48 s on suzanne, the first mesh of benchmarks/bench_pack.py); at
    # bd_uv's import it would add ~0.1 s to every process that never packs
    import scipy.optimize  # noqa: F401
    t0 = clock()
    k = len(outlines)
    owner, nxt = _rings(outlines)
    radius = np.array([np.sqrt((o ** 2).sum(axis=1).max()) for o in outlines])
    turn = options.rotate == "any"
    pm = options.padding + MARGIN
    angle, shift, S = placement.angle.copy(), placement.shift.copy(), float(side)
    step, steps = STEP * side, 0
    if k < 2 or not fits(outlines, angle, shift, S, options.padding, options.padding, tol):
        return placement, side, 0
    programs = moves = 0
    history = [(0.0, S)]   # (CPU seconds, side) before each program
    hold = [False]         # (HOLD) set at the first infeasible program, for the rest
    while True:  # per local optimum: compaction, then the bounding small charts moved in
        until = seconds if max_programs is not None or moves else RELOCATE_AT * seconds
        S, angle, shift, step, programs, steps = _programs(
            outlines, owner, nxt, radius, turn, pm, tol, options, angle, shift, S, step,
            programs, steps, history, t0, until, STALL_SHARE * seconds, max_programs,
            least_side, side, hold, seconds, clock, cancel)
        # converged, stalled or at RELOCATE_AT of the time (not in a run bounded by programs):
        # the small charts against the square's edges into the free space deepest inside it,
        # and on
        if (max_programs is not None
                or _over(history, clock() - t0, S, seconds, seconds,
                         STALL_SHARE * seconds)
                or (cancel is not None and cancel.is_set())
                or S <= least_side * (1 + NEAR_LEAST) or moves >= MOVE_ROUNDS):
            break
        moved_angle, moved_shift, moved = relocate(outlines, angle, shift, S, pm * S + 2 * tol,
                                                   options)
        moves = moves + 1 if moved else MOVE_ROUNDS   # (nothing moved: compaction to the end)
        if moved and fits(outlines, moved_angle, moved_shift, S, options.padding, pm, tol):
            angle, shift, step = moved_angle, moved_shift, STEP * side
            history[:] = [(clock() - t0, S)]   # a stall is judged afresh
    shift, S = anchored(outlines, angle, shift, S, options.padding, pm, tol)
    return Placement(angle, shift, S), S, steps


def _programs(outlines, owner, nxt, radius, turn, pm, tol, options, angle, shift, S, step,
              programs, steps, history, t0, seconds, window, max_programs, least_side, side,
              hold, budget, clock=time.process_time, cancel=None):
    """Compaction steps until ``seconds`` of CPU since ``t0`` are spent (the run's whole
    ``budget``: past it while the side still shrinks, :func:`_over`) or ``max_programs`` are,
    the step falls below ``LEAST_STEP`` of the side, the side nears ``least_side`` or the side
    stalls over ``window`` seconds: the side, turns, shifts, step, programs and steps
    reached. ``hold``: [bool], whether the programs hold the turns of tight pairs (``HOLD``),
    set here at the first infeasible one. ``clock``: the CPU clock; ``cancel``: an Event that
    ends the steps once set."""
    if max_programs is not None:
        budget = np.inf   # (a run bounded by programs: never past ``seconds``)
    while (not _over(history, clock() - t0, S, seconds, budget, window)
           and not (cancel is not None and cancel.is_set())
           and step > LEAST_STEP * side
           and S > least_side * (1 + NEAR_LEAST)
           and (max_programs is None or programs < max_programs)
           and not (max_programs is None and _stalled(history, clock() - t0, S, window))):
        history.append((clock() - t0, S))
        programs += 1
        Q = _placed(outlines, angle, shift)
        extra = None
        for again in (False, True):  # the program, then once more with the pairs it missed
            got, infeasible = step_lp(Q, owner, nxt, shift, radius, S, options.padding, pm, tol,
                                       step, turn, _left(seconds, budget, t0, clock), extra,
                                       hold[0])
            if infeasible and turn and not hold[0]:
                # the turns' error terms exceed some gaps no move can widen: from now on the
                # small charts of those pairs do not turn (HOLD)
                hold[0] = True
                got, _ = step_lp(Q, owner, nxt, shift, radius, S, options.padding, pm, tol,
                                  step, turn, _left(seconds, budget, t0, clock), extra, True)
            if got is None or got[2] > S * (1 - REL_GAIN):
                break   # (the turns' error bound can block a long step)
            move, phi, S_new = got
            # a turn is about the chart's centre (its outline is centred on shift)
            full = (angle + np.rad2deg(phi), shift + move, S_new)
            checked = not again and fits(outlines, *full, options.padding, pm, tol)
            if again or checked:
                break
            # pairs closer than the separation after the move, out of reach before it: rows
            # for them too (the points move up to 2 (sqrt 2 + 1) steps apart, beyond
            # compact_step.REACH)
            near = close(_placed(outlines, full[0], full[1]), owner, nxt,
                          pm * S_new + 2 * tol + step)
            extra = near if extra is None else tuple(np.concatenate(z) for z in zip(extra, near))
            programs += 1
        if got is None or got[2] > S * (1 - REL_GAIN):
            step *= 0.5
            continue
        # the move, else part of it (the linear model holds on the segment to it; the exact
        # check decides)
        for part in LINE_SEARCH:  # per fraction of the move (the whole one maybe checked)
            new = (angle + part * np.rad2deg(phi), shift + part * move, S + part * (S_new - S))
            if (part == 1 and checked) or fits(outlines, *new, options.padding, pm, tol):
                angle, shift, S = new
                steps += 1
                break
        step = min(2 * step, STEP * side) if part == 1 else step * 0.5
    return S, angle, shift, step, programs, steps


def _over(history, now, side, until, budget, window):
    """Whether a run to ``until`` CPU seconds is over ``now``: at ``until``; but where
    ``until`` is the whole ``budget``, a side that shrank by ``STALL_GAIN`` or more (relative)
    over the last ``window`` seconds of the ``history`` [(seconds, side before that program),
    ...] goes on, up to ``EXTEND`` times the budget."""
    if now < until:
        return False
    if until < budget or now >= EXTEND * budget:
        return True
    before = [s for t, s in history if t <= now - window]
    return not (before and before[-1] >= side * (1 + STALL_GAIN))


def _left(until, budget, t0, clock=time.process_time):
    """CPU seconds left to a program's solve: to ``until``; once past the whole ``budget``
    (where ``until`` is it: the run goes on while the side shrinks, :func:`_over`), to
    ``EXTEND`` times the budget. (A program is cut at the budget as before: with the longer
    limit from the start ChineseDragon's compaction of 116 charts spent its time on long
    programs of large steps, 1.5 % less area.)"""
    now = clock() - t0
    end = EXTEND * budget if budget <= until <= now else until
    return end - now


def _stalled(history, now, side, window):
    """True when the side shrank by less than ``STALL_GAIN`` (relative) to ``side`` over the
    last ``window`` CPU seconds (``now``: seconds since the start) of the compaction's
    ``history`` [(seconds, side before that program), ...]."""
    if now < window or not history:
        return False
    before = [s for t, s in history if t <= now - window]
    return bool(before) and before[-1] < side * (1 + STALL_GAIN)
