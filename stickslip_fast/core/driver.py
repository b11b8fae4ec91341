"""The one adaptive driver: step control, observers and stop rules over any problem.

:func:`drive` integrates a problem record (:mod:`stickslip_fast.problems`) with
a method record (:mod:`stickslip_fast.steppers`) from t = 0 until ``t_end``, a
stop rule fires, or something fails. After every accepted step it calls an
*observer*, which records what it needs (Poincare points, samples, renormalised
tangent vectors) and may modify the new state; then it asks the *stop rule*
whether to end. Observers and stop rules are records too, dispatched on their
type like problems:

``observe_start(obs, y)``
    Once, before the first step (may modify y).
``observe_step(obs, method, ws, t0, h, y0, y1) -> int``
    After each accepted step [t0, t0 + h] from y0 to y1; may build the step's
    dense output (``stepper_dense``) and modify y1. Returns a bit set of
    ``OBS_MODIFIED`` (y1 changed) and ``OBS_FAIL`` (stop with "nonfinite").
``stop_now(stop, obs, t, y) -> bool``
    After each accepted step (and its observation).

Guarantees (the kernel rules)
-----------------------------
The driver never raises and every loop is bounded: accepted steps by
``max_steps`` ("max-steps"), rejected steps by ``max_steps`` as well, a step
size that shrinks below 1e-14 |t| or is not a number ends the run
("step-underflow" or "nonfinite"), and ``abort[0] != 0``, set from another
thread (Ctrl-C), ends it within one step ("interrupted").
"""

from __future__ import annotations

import math
from collections import namedtuple

import numpy as np
from numba import njit
from numba.extending import overload

from ..base.jit import JIT, OVERLOAD, borrow, is_record, poll_flag
from ..base.status import (
    ST_INTERRUPTED,
    ST_MAX_STEPS,
    ST_NONFINITE,
    ST_OK,
    ST_UNDERFLOW,
)
from .poincare import ring_period
from .problems import problem_error_norm, problem_initial_step
from .steppers import (
    accepted_step_factor,
    dense_state,
    dense_value,
    rejected_step_factor,
    stepper_accept,
    stepper_dense,
    stepper_dense_kind,
    stepper_init,
    stepper_step,
)

__all__ = [
    "Controls",
    "Section",
    "PoincareObserver",
    "StopRule",
    "STOP_AT_END",
    "STOP_AFTER_CROSSINGS",
    "fixed_stop",
    "rest_time",
    "disk1_rest_time",
    "time_since_crossing",
    "OBS_MODIFIED",
    "OBS_FAIL",
    "drive",
    "observe_start",
    "observe_step",
    "stop_now",
    "locate_crossing",
]

_JIT = JIT
_OVL = OVERLOAD

OBS_MODIFIED = 1
OBS_FAIL = 2

#: Step-size control: tolerances, a fixed step (``h_fixed`` > 0 turns any method
#: into a fixed-step one), the bound on accepted (and on rejected) steps.
Controls = namedtuple("Controls", ["rtol", "atol", "h_fixed", "max_steps"])
#: A Poincare section y[component] = 0, crossed upwards (``up``) or downwards.
Section = namedtuple("Section", ["component", "up"])
#: Records crossings of ``section`` after ``t_transient`` into the ring buffer
#: ``pts``/``tpts`` (the most recent ones), uniform samples every ``sample_dt``
#: from ``t_transient`` into ``samples``, and the range ``ymin``/``ymax`` of the
#: state over the window. ``counts`` = (crossings, samples).
PoincareObserver = namedtuple(
    "PoincareObserver",
    ["section", "t_transient", "pts", "tpts", "samples", "sample_dt", "ymin", "ymax", "counts"],
)
#: When to end a run before ``t_end``. ``kind``: STOP_AT_END (never),
#: STOP_AFTER_CROSSINGS (once ``count`` crossings are recorded), or
#: STOP_CONVERGED (see :func:`converged_stop`): the recorded points repeat with
#: a period <= ``max_period`` to ``period_tol`` over ``min_repeats`` periods and
#: at least ``min_points`` points, or the disks have been at rest (speeds, and
#: the belt-speed range, <= ``equilibrium_tol``) for ``dwell`` time units; then
#: max(min_points, 4 periods) more crossings are recorded, at most the ring
#: buffer's capacity (orbit), or the run ends (rest).
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
STATE_SIZE = 9

C_CROSS, C_SAMPLES = 0, 1


_is = is_record


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
def fixed_stop(equilibrium_tol, n_osc, dc, n) -> StopRule:
    """A STOP_AT_END rule that watches for rest (see :func:`rest_time`)."""
    return StopRule(
        STOP_AT_END, 0, 0.0, 0, 0, 0, equilibrium_tol, 0.0, n_osc, dc, np.empty(n), np.empty(n),
        np.zeros(STATE_SIZE),
    )  # fmt: skip


@njit(**_JIT)
def _reset_stop(stop, y) -> None:
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
        _track_rest(stop, 0.0, y)  # a start at rest is at rest from t = 0


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


@njit(inline="always", **_JIT)
def _elapsed(since: float, t: float, never: float) -> float:
    """t - since, or ``never`` when ``since`` is unset (NaN)."""
    if math.isnan(since):
        return never
    return t - since


@njit(inline="always", **_JIT)
def _at_rest(stop, y) -> bool:
    tol = stop.equilibrium_tol
    for i in range(stop.n_osc):
        if not (abs(y[4 * i + 1]) <= tol and abs(y[4 * i + 3]) <= tol):
            return False
    return True


@njit(inline="always", **_JIT)
def _track_rest(stop, t, y) -> bool:
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


@njit(inline="always", **_JIT)
def _converged_now(stop, obs, t, y) -> bool:
    """STOP_CONVERGED: watch for rest and for repeating points; see :class:`StopRule`."""
    st = stop.state
    n = y.size
    if st[S_PHASE] == 1.0:
        if stop.n_osc > 0:
            _track_rest(stop, t, y)  # the run's classification reads the rest time
        return obs.counts[C_CROSS] >= st[S_TARGET]
    # rest: disk speeds within the tolerance, and the belt speed's range, for `dwell`
    if _track_rest(stop, t, y) and t - st[S_REST_SINCE] >= stop.dwell:
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
        # at rest, dx1 flickers around 0 at round-off and gives repeating "points":
        # rest is judged by its dwell window above, never from points
        if per > 0 and not _at_rest(stop, y):
            st[S_PHASE] = 1.0
            st[S_T_CONVERGED] = t
            st[S_PERIOD] = per
            cap = obs.pts.shape[0]
            st[S_TARGET] = min(cap, max(stop.min_points, 4 * per))
            # a fresh recording window from here: the points after convergence
            obs.counts[C_CROSS] = 0
            for i in range(n):
                obs.ymin[i] = y[i]
                obs.ymax[i] = y[i]
    return False


# ------------------------------------------------------------------ section
@njit(inline="always", **_JIT)
def locate_crossing(kind: int, y0, y1, D, comp: int, up: bool) -> float:
    """theta in [0, 1] where component ``comp`` of the dense output crosses 0.

    Requires s y0[comp] < 0 <= s y1[comp] with s = +1 (``up``) or -1. Illinois
    method: superlinear, bracketing, at most 200 iterations, stops when the
    bracket no longer shrinks in floating point.
    """
    sgn = 1.0 if up else -1.0
    a = 0.0
    fa = y0[comp] if up else -y0[comp]
    b = 1.0
    fb = y1[comp] if up else -y1[comp]
    if fb == 0.0:
        return 1.0
    side = 0
    theta = 1.0
    for _ in range(200):
        theta = (a * fb - b * fa) / (fb - fa)
        if not (a < theta < b):
            theta = 0.5 * (a + b)
            if not (a < theta < b):
                break
        f = dense_value(kind, theta, y0, y1, D, comp)
        if not up:
            f = sgn * f
        if f == 0.0:
            return theta
        if f < 0.0:
            a = theta
            fa = f
            if side == -1:
                fb *= 0.5
            side = -1
        else:
            b = theta
            fb = f
            if side == 1:
                fa *= 0.5
            side = 1
        if b - a <= 4e-16:
            break
    return theta


@njit(inline="always", **_JIT)
def _crosses(section, y0, y1) -> bool:
    c = section.component
    if section.up:
        return y0[c] < 0.0 <= y1[c]
    return y0[c] > 0.0 >= y1[c]


# ----------------------------------------------------------- generic functions
def observe_start(obs, y):  # noqa: ARG001 - resolved by overload
    """Called once before the first step."""


def observe_step(obs, method, ws, t0, h, y0, y1):  # noqa: ARG001
    """Called after each accepted step; returns OBS_* flags."""


def stop_now(stop, obs, t, y):  # noqa: ARG001
    """True to end the run after this step."""


@overload(observe_start, **_OVL)
def _poincare_start(obs, y):
    if _is(obs, PoincareObserver):

        def impl(obs, y):
            n = obs.ymin.size
            obs.counts[C_CROSS] = 0
            obs.counts[C_SAMPLES] = 0
            for i in range(n):
                obs.ymin[i] = np.inf
                obs.ymax[i] = -np.inf
            if obs.samples.shape[0] > 0 and obs.t_transient <= 0.0:
                for i in range(n):
                    obs.samples[0, i] = y[i]
                obs.counts[C_SAMPLES] = 1
            if obs.t_transient <= 0.0:
                for i in range(n):
                    obs.ymin[i] = y[i]
                    obs.ymax[i] = y[i]

        return impl


@overload(observe_step, **_OVL)
def _poincare_step(obs, method, ws, t0, h, y0, y1):
    if _is(obs, PoincareObserver):

        def impl(obs, method, ws, t0, h, y0, y1):
            n = obs.ymin.size
            n_cross = obs.counts[C_CROSS]
            n_samp = obs.counts[C_SAMPLES]
            n_grid = obs.samples.shape[0]
            crossing = _crosses(obs.section, y0, y1)
            # dense output only where a crossing or a sample needs it
            if crossing or (n_samp < n_grid and obs.t_transient + n_samp * obs.sample_dt <= t0 + h):
                stepper_dense(method, ws, h)
            kind = stepper_dense_kind(method)
            D = ws.D
            t1 = t0 + h
            if crossing:
                theta = locate_crossing(kind, y0, y1, D, obs.section.component, obs.section.up)
                tc = t0 + theta * h
                if tc >= obs.t_transient:
                    cap = obs.pts.shape[0]
                    if cap > 0:
                        slot = n_cross % cap
                        dense_state(kind, theta, y0, y1, D, obs.pts[slot])
                        obs.tpts[slot] = tc
                    n_cross += 1
            # uniform samples on t_transient + k * sample_dt
            while n_samp < n_grid:
                ts = obs.t_transient + n_samp * obs.sample_dt
                if ts > t1:
                    break
                theta = (ts - t0) / h
                theta = min(1.0, max(0.0, theta))
                dense_state(kind, theta, y0, y1, D, obs.samples[n_samp])
                n_samp += 1
            # range of the motion over the recording window
            if t1 >= obs.t_transient:
                for i in range(n):
                    v = y1[i]
                    if v < obs.ymin[i]:
                        obs.ymin[i] = v
                    if v > obs.ymax[i]:
                        obs.ymax[i] = v
            obs.counts[C_CROSS] = n_cross
            obs.counts[C_SAMPLES] = n_samp
            return 0

        return impl


@overload(stop_now, **_OVL)
def _stop_now(stop, obs, t, y):
    if _is(stop, StopRule) and _is(obs, PoincareObserver):

        def impl(stop, obs, t, y):
            if stop.n_osc > 0:
                # (converged stopping resets the count: only an increase is a crossing)
                if obs.counts[C_CROSS] > stop.state[S_N_SEEN]:
                    stop.state[S_LAST_CROSSING] = t
                stop.state[S_N_SEEN] = obs.counts[C_CROSS]
            if stop.kind == STOP_AFTER_CROSSINGS:
                return obs.counts[C_CROSS] >= stop.count
            if stop.kind == STOP_CONVERGED:
                return _converged_now(stop, obs, t, y)
            if stop.kind == STOP_AT_END and stop.n_osc > 0:
                _track_rest(stop, t, y)
            return False

        return impl


# ----------------------------------------------------------------------- driver
@njit(**_JIT)
def drive(method, prob, lin, ws, y, t_end, ctl, obs, stop, abort, istat, fstat) -> int:
    """Integrate ``y`` (in place) from t = 0 to ``t_end``; returns a status code.

    ``method``: a method record; ``prob``/``lin``: a problem record and its linear
    workspace; ``ws``: a :class:`StepWorkspace` of the method; ``ctl``:
    :class:`Controls`; ``obs``/``stop``: an observer and a stop rule; ``abort``:
    int64[1], polled every step. On return ``y`` is the state at the last accepted
    time, ``istat`` = (accepted, rejected) and ``fstat[0]`` = that time. Status:
    ST_OK (reached t_end or the stop rule fired), ST_MAX_STEPS, ST_UNDERFLOW,
    ST_NONFINITE or ST_INTERRUPTED.
    """
    # Borrowed records: the step loop below copies them into every inlined call,
    # and each copy of a counted array costs an atomic instruction (jit.borrow).
    method = borrow(method)
    prob = borrow(prob)
    lin = borrow(lin)
    ws = borrow(ws)
    y = borrow(y)
    obs = borrow(obs)
    stop = borrow(stop)
    n = y.size
    q = method.q
    rtol = ctl.rtol
    atol = ctl.atol
    max_steps = ctl.max_steps
    observe_start(obs, y)
    _reset_stop(stop, y)
    stepper_init(method, prob, lin, y, ws)
    adaptive = ctl.h_fixed <= 0.0
    if adaptive:
        h = problem_initial_step(prob, y, ws.f0, rtol, atol, q - 1.0, ws.ytmp, ws.ftmp)
        h = min(h, t_end)
    else:
        h = ctl.h_fixed
    n_steps = 0
    n_rej = 0
    status = ST_OK
    t = 0.0
    err_prev = 1.0
    en = 0.0
    last_rejected = False
    ynew = ws.ynew

    while t < t_end:
        if poll_flag(abort) != 0:
            status = ST_INTERRUPTED
            break
        if n_steps >= max_steps or n_rej >= max_steps:
            status = ST_MAX_STEPS
            break
        # land exactly on t_end; avoid a sliver of a last step
        if t + h >= t_end or (adaptive and t + 1.01 * h >= t_end):
            h = t_end - t
        ok = stepper_step(method, prob, lin, y, h, ws)
        if ok:
            for i in range(n):
                if not math.isfinite(ynew[i]):
                    ok = False
                    break
        if not adaptive:
            if not ok:
                status = ST_NONFINITE
                break
            en = 0.0
        elif ok:
            en = problem_error_norm(prob, ws.err, y, ynew, rtol, atol)
            if not math.isfinite(en):
                ok = False
        if adaptive and (not ok or en > 1.0):
            n_rej += 1
            h *= rejected_step_factor(en, ok, q)
            last_rejected = True
            # "not >=" also catches a step size that is not a number
            if not (h >= 1e-14 * max(1.0, abs(t))):
                status = ST_UNDERFLOW if ok else ST_NONFINITE
                break
            continue

        n_steps += 1
        flags = observe_step(obs, method, ws, t, h, y, ynew)
        t = t + h
        for i in range(n):
            y[i] = ynew[i]
        if flags & OBS_FAIL:
            status = ST_NONFINITE
            break
        stepper_accept(method, prob, lin, y, ws, (flags & OBS_MODIFIED) != 0)
        if adaptive:
            h *= accepted_step_factor(en, err_prev, q, last_rejected)
            err_prev = max(en, 1e-10)
            last_rejected = False
        if stop_now(stop, obs, t, y):
            break

    istat[0] = n_steps
    istat[1] = n_rej
    fstat[0] = t
    return status
