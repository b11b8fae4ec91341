"""The one adaptive driver: step control, observers and stop rules over any problem.

:func:`drive` integrates a problem record (:mod:`stickslip_fast.core.problems`) with
a method record (:mod:`stickslip_fast.core.steppers`) from t = 0 until ``t_end``, a
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

from ..base.jit import JIT, borrow, is_record, njit, overload_call, poll_flag
from ..base.status import (
    ST_INTERRUPTED,
    ST_MAX_STEPS,
    ST_NONFINITE,
    ST_OK,
    ST_UNDERFLOW,
)
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
from .stoprules import (  # noqa: F401  (re-exported: the stop rules used to live here)
    PHASE_PAST_END,
    S_LAST_CROSSING,
    S_N_SEEN,
    S_PHASE,
    S_T_CONVERGED,
    S_T_END,
    STOP_AFTER_CROSSINGS,
    STOP_AT_END,
    STOP_CONVERGED,
    StopRule,
    converged_now,
    converged_stop,
    disk1_rest_time,
    fixed_stop,
    past_end,
    reset_stop,
    rest_time,
    simple_stop,
    stop_now,
    time_since_crossing,
    track_rest,
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
from .stoprules import C_CROSS, C_SAMPLES  # noqa: E402  (the observer's count slots)

_is = is_record


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


@overload_call(observe_start)
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


@overload_call(observe_step)
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


@overload_call(stop_now)
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
            if stop.state[S_PHASE] != PHASE_PAST_END:
                if stop.kind == STOP_CONVERGED:
                    if converged_now(stop, obs, t, y):
                        return True
                elif stop.kind == STOP_AT_END and stop.n_osc > 0:
                    track_rest(stop, t, y)
                if t < stop.state[S_T_END]:
                    return False
            # the window's last step, or past it: a run whose label is undecided goes on
            if stop.n_osc > 0:
                return past_end(stop, t, y, obs.t_transient)
            return False

        return impl


# ----------------------------------------------------------------------- driver
@njit(**_JIT)
def drive(method, prob, lin, ws, y, t_end, ctl, obs, stop, abort, istat, fstat) -> int:
    """Integrate ``y`` (in place) from t = 0 to ``t_end``; returns a status code.

    (A stop rule may move the end: ``stop.state[S_T_END]``, which the driver sets to
    ``t_end`` and reads after each step; see :func:`stoprules.past_end`.)

    ``method``: a method record; ``prob``/``lin``: a problem record and its linear
    workspace; ``ws``: a :class:`StepWorkspace` of the method; ``ctl``:
    :class:`Controls`; ``obs``/``stop``: an observer and a stop rule; ``abort``:
    int64[1], polled every step. On return ``y`` is the state at the last accepted
    time, ``istat`` = (accepted, rejected) and ``fstat[0]`` = that time. Status:
    ST_OK (reached t_end or the stop rule fired), ST_MAX_STEPS, ST_UNDERFLOW,
    ST_NONFINITE or ST_INTERRUPTED.
    """
    # Borrowed records: the step loop below passes them to every call, and each
    # copy of a counted array costs an atomic instruction (jit.borrow).
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
    reset_stop(stop, y)
    stop.state[S_T_END] = t_end
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
        t_end = stop.state[S_T_END]  # a stop rule may look past the end (past_end)

    istat[0] = n_steps
    istat[1] = n_rej
    fstat[0] = t
    return status
