"""Stop rules of the driver: when a run ends, and what it has seen of rest and crossings.

A stop rule is a record (:class:`StopRule`) that :func:`stop_now` asks after
every accepted step. Every rule made for a trajectory (:func:`fixed_stop`,
:func:`converged_stop`) also watches the run for the classification
(:func:`~stickslip_fast.core.poincare.classify`): how long the disks, and disk 1
alone, have been at rest (:func:`rest_time`, :func:`disk1_rest_time`) and when
the last crossing was (:func:`time_since_crossing`).
"""

from __future__ import annotations

import math
from collections import namedtuple

import numpy as np

from ..base.jit import JIT, njit
from .poincare import ring_period, undecided

__all__ = [
    "StopRule",
    "STOP_AT_END",
    "STOP_AFTER_CROSSINGS",
    "STOP_CONVERGED",
    "simple_stop",
    "fixed_stop",
    "converged_stop",
    "past_end",
    "reset_stop",
    "rest_time",
    "disk1_rest_time",
    "time_since_crossing",
    "stop_now",
]

_JIT = JIT

#: Slots of an observer's ``counts``: (crossings recorded, samples taken).
C_CROSS, C_SAMPLES = 0, 1

#: When to end a run before ``t_end``. ``kind``: STOP_AT_END (never),
#: STOP_AFTER_CROSSINGS (once ``count`` crossings are recorded), or
#: STOP_CONVERGED (see :func:`converged_stop`): the recorded points repeat with
#: a period <= ``max_period`` to ``period_tol`` over ``min_repeats`` periods and
#: at least ``min_points`` points, and have stopped drifting (``ring_period``),
#: while disk 1 moves between crossings; or the disks have been at rest (speeds,
#: and the belt-speed range, <= ``equilibrium_tol``) for ``dwell`` time units;
#: then max(min_points, 4 periods) more crossings are recorded, at most the ring
#: buffer's capacity, and the run ends at a step where disk 1 moves (orbit), or
#: the run ends (rest).
#: ``wmin``/``wmax`` (n,) and ``state`` (STATE_SIZE,) are its working memory.
StopRule = namedtuple(
    "StopRule",
    [
        "kind", "count", "period_tol", "max_period", "min_repeats", "min_points",
        "equilibrium_tol", "dwell", "n_osc", "dc", "wmin", "wmax", "state",
    ],
)  # fmt: skip
STOP_AT_END = 0
STOP_AFTER_CROSSINGS = 1
STOP_CONVERGED = 2
# slots of StopRule.state
S_PHASE, S_T_CONVERGED, S_REST_SINCE, S_CHECKED, S_TARGET, S_PERIOD = range(6)
# rules that watch the run (n_osc > 0): the crossings seen, and the step end of the last one
S_N_SEEN, S_LAST_CROSSING = 6, 7
# ... and since when disk 1 (whose x1 minima are the section) has been at rest
S_DISK1_REST_SINCE = 8
# the run's t_end (set by the driver at its start; converged stopping reads it, and
# a run that looks past its end moves it: the driver runs until it)
S_T_END = 9
STATE_SIZE = 10
#: S_PHASE of a run that looks past the end of its window (:func:`past_end`)
PHASE_PAST_END = 2.0


@njit(**_JIT)
def simple_stop(kind: int, count: int, n: int) -> StopRule:
    """A STOP_AT_END or STOP_AFTER_CROSSINGS rule."""
    return StopRule(
        kind, count, 0.0, 0, 0, 0, 0.0, 0.0, 0, False, np.empty(n), np.empty(n),
        np.zeros(STATE_SIZE),
    )  # fmt: skip


@njit(**_JIT)
def converged_stop(
    period_tol, max_period, min_repeats, min_points, equilibrium_tol, dwell, n_osc, dc, n
) -> StopRule:
    """A STOP_CONVERGED rule (after convergence: max(min_points, 4 periods) more points)."""
    return StopRule(
        STOP_CONVERGED, 0, period_tol, max_period, min_repeats, min_points,
        equilibrium_tol, dwell, n_osc, dc, np.empty(n), np.empty(n), np.zeros(STATE_SIZE),
    )  # fmt: skip


@njit(**_JIT)
def fixed_stop(equilibrium_tol, dwell, n_osc, dc, n) -> StopRule:
    """A STOP_AT_END rule that watches for rest (see :func:`rest_time`) and looks past
    the end of the window while the run's label is undecided (see :func:`past_end`)."""
    return StopRule(
        STOP_AT_END, 0, 0.0, 0, 0, 0, equilibrium_tol, dwell, n_osc, dc, np.empty(n),
        np.empty(n), np.zeros(STATE_SIZE),
    )  # fmt: skip


@njit(**_JIT)
def reset_stop(stop, y) -> None:
    stop.state[S_PHASE] = 0.0
    stop.state[S_T_CONVERGED] = np.nan
    stop.state[S_REST_SINCE] = np.nan
    stop.state[S_CHECKED] = -1.0
    stop.state[S_TARGET] = 0.0
    stop.state[S_PERIOD] = 0.0
    stop.state[S_N_SEEN] = 0.0
    stop.state[S_LAST_CROSSING] = np.nan
    stop.state[S_DISK1_REST_SINCE] = np.nan
    if stop.kind == STOP_AT_END and stop.n_osc > 0:
        track_rest(stop, 0.0, y)  # a start at rest is at rest from t = 0


@njit(**_JIT)
def rest_time(stop, t: float) -> float:
    """How long the run has been at rest at time ``t``; -1.0 if it is moving.

    At rest: every disk speed |dx_i|, |dphi_i| <= ``equilibrium_tol`` and, on a
    DC motor, the belt speed's range since then <= ``equilibrium_tol``. Tracked
    by STOP_AT_END rules made by :func:`fixed_stop` and by STOP_CONVERGED rules
    (those from the first step on); -1.0 for other rules.
    """
    return _elapsed(stop.state[S_REST_SINCE], t, -1.0)


@njit(**_JIT)
def disk1_rest_time(stop, t: float) -> float:
    """As :func:`rest_time`, for disk 1 alone (|dx_1|, |dphi_1| <= ``equilibrium_tol``)."""
    return _elapsed(stop.state[S_DISK1_REST_SINCE], t, -1.0)


@njit(**_JIT)
def time_since_crossing(stop, t: float) -> float:
    """Time from the end of the step of the last recorded crossing to ``t`` (inf if none).

    Tracked by the rules that :func:`rest_time` names.
    """
    return _elapsed(stop.state[S_LAST_CROSSING], t, np.inf)


# The helpers below are compiled functions of their own, not IR-inlined ones: IR-inlined
# at each call site (track_rest and _at_rest twice each), Numba copied and re-typed them
# into stop_now, 4.4 s of a first simulate's compile; as calls, 2.1 s in all, with the
# warm run unchanged within noise (docs/performance.md, "The first run").
@njit(**_JIT)
def _elapsed(since: float, t: float, never: float) -> float:
    """t - since, or ``never`` when ``since`` is unset (NaN)."""
    if math.isnan(since):
        return never
    return t - since


@njit(**_JIT)
def _at_rest(stop, y) -> bool:
    tol = stop.equilibrium_tol
    for i in range(stop.n_osc):
        if not (abs(y[4 * i + 1]) <= tol and abs(y[4 * i + 3]) <= tol):
            return False
    return True


@njit(**_JIT)
def track_rest(stop, t, y) -> bool:
    """Update the start of the current stretch at rest (``S_REST_SINCE``); True if at rest.

    ``wmin``/``wmax`` hold the state's range over the stretch; on a DC motor a
    belt speed that varies by more than ``equilibrium_tol`` restarts it.
    """
    st = stop.state
    n = y.size
    tol = stop.equilibrium_tol
    if abs(y[1]) <= tol and abs(y[3]) <= tol:
        if math.isnan(st[S_DISK1_REST_SINCE]):
            st[S_DISK1_REST_SINCE] = t
    else:
        st[S_DISK1_REST_SINCE] = np.nan
    if not _at_rest(stop, y):
        st[S_REST_SINCE] = np.nan
        return False
    if math.isnan(st[S_REST_SINCE]):
        st[S_REST_SINCE] = t
        for i in range(n):
            stop.wmin[i] = y[i]
            stop.wmax[i] = y[i]
        return True
    for i in range(n):
        stop.wmin[i] = min(stop.wmin[i], y[i])
        stop.wmax[i] = max(stop.wmax[i], y[i])
    if stop.dc and stop.wmax[n - 1] - stop.wmin[n - 1] > stop.equilibrium_tol:
        st[S_REST_SINCE] = t
        for i in range(n):
            stop.wmin[i] = y[i]
            stop.wmax[i] = y[i]
    return True


@njit(**_JIT)
def converged_now(stop, obs, t, y) -> bool:
    """STOP_CONVERGED: watch for rest and for repeating points; see :class:`StopRule`."""
    st = stop.state
    n = y.size
    if st[S_PHASE] == 1.0:
        if stop.n_osc > 0:
            track_rest(stop, t, y)  # the run's classification reads the rest time
        if obs.counts[C_CROSS] < st[S_TARGET]:
            return False
        # End where disk 1 moves: near its x1 minimum an orbit's speeds can all be below
        # equilibrium_tol, and a run that ended there would read as just come to rest.
        return math.isnan(st[S_DISK1_REST_SINCE]) or rest_time(stop, t) >= stop.dwell
    # rest: disk speeds within the tolerance, and the belt speed's range, for `dwell`
    if track_rest(stop, t, y) and t - st[S_REST_SINCE] >= stop.dwell:
        # the recording window is the dwell window
        for i in range(n):
            obs.ymin[i] = stop.wmin[i]
            obs.ymax[i] = stop.wmax[i]
        st[S_T_CONVERGED] = st[S_REST_SINCE]
        return True
    # repeating points: checked once per new crossing
    c = obs.counts[C_CROSS]
    if c != st[S_CHECKED]:
        st[S_CHECKED] = c
        per = ring_period(
            obs.pts, c, stop.period_tol, stop.max_period, stop.min_repeats, stop.min_points
        )
        if per == 0:
            return False
        # Not the round-off flicker of dx1 at rest: then the disks are at rest and disk 1
        # (whose x1 minima are the section) has been since before the previous crossing.
        # The state at a crossing alone cannot tell, as dx1 = 0 there by definition: an
        # orbit whose |dphi1| stays below equilibrium_tol looks at rest at each of its
        # crossings, though disk 1 moves between them (issue 30's GPU rerun found such
        # runs never converging). (Inline, as below: each compiled helper costs every
        # first run its compile, docs/performance.md.)
        cap = obs.tpts.shape[0]
        since = st[S_DISK1_REST_SINCE]
        if _at_rest(stop, y) and not since > obs.tpts[(c - 2) % cap]:  # (since is set then)
            return False
        # The points to record after convergence must fit before t_end at the pace of the
        # last period; else the run goes on unconverged and is judged at t_end from all
        # its points, as a fixed window is (Fig. 14 at eta = 5.45 converged at t = 4911
        # of 5000 and came back with no period).
        target = min(obs.pts.shape[0], max(stop.min_points, 4 * per))
        pace = (obs.tpts[(c - 1) % cap] - obs.tpts[(c - 1 - per) % cap]) / per
        if t + (target + 1) * pace <= st[S_T_END]:
            st[S_PHASE] = 1.0
            st[S_T_CONVERGED] = t
            st[S_PERIOD] = per
            st[S_TARGET] = target
            # a fresh recording window from here: the points after convergence
            obs.counts[C_CROSS] = 0
            for i in range(n):
                obs.ymin[i] = y[i]
                obs.ymax[i] = y[i]
    return False


@njit(**_JIT)
def past_end(stop, t, y, t_rec) -> bool:
    """The rule at the last step of the window (t >= ``S_T_END``) and after it.

    A window can end where the run's label cannot be told yet
    (:func:`poincare.undecided`):

    - while the run is settling (at rest, or disk 1 at rest, for less than the tail of
      the classification), which would leave it "unsettled". Near the Hopf point a
      small orbit's speeds all dip below ``equilibrium_tol`` near each extremum of x1,
      and a window that ends in such a dip sees a run that has just come to rest;
    - while disk 1 moves but its last crossing was longer than the tail ago, which
      would make it "no-crossings". An orbit whose x1 minima are further apart than
      ``dwell`` (a slow period 2 of the literature set: 229.9 and 6.3 time units)
      looks so between two of them.

    Such a run goes on, for at most ``dwell`` more time units, and ends at the first
    step where its label is decided: a crossing, disk 1 moving again (its crossings
    then decide, as for any run), or rest that has lasted the tail. A run that is
    decided at the end of its window ends there, as before. ``t_rec`` is the start of
    the recording window. Returns True to end the run. (Converged stopping has had its
    say at the window's last step before this is asked.)
    """
    st = stop.state
    if st[S_PHASE] == PHASE_PAST_END:
        track_rest(stop, t, y)
    tail = min(stop.dwell, t - t_rec)
    since = time_since_crossing(stop, t)
    waiting = undecided(rest_time(stop, t), disk1_rest_time(stop, t), since, tail)
    if waiting and st[S_PHASE] != PHASE_PAST_END:
        st[S_PHASE] = PHASE_PAST_END
        st[S_T_END] += stop.dwell
        return False
    return not waiting


# ------------------------------------------------------------------ section


def stop_now(stop, obs, t, y):  # noqa: ARG001
    """True to end the run after this step (the overload for the Poincare
    observer is in :mod:`.driver`, beside that observer)."""
