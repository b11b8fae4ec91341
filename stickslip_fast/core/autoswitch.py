"""``method="auto"``: Dormand-Prince 5(4) while the motion is non-stiff, Rodas5P while it is stiff.

The idea of LSODA and of OrdinaryDiffEq.jl's auto-switching solvers, on the
engine's two order-5(4) methods. :data:`AUTO_METHOD` is a method record like
those of :mod:`.steppers`, with its own overloads of the generic stepper
functions, so :func:`.driver.drive` and every observer run it unchanged. Its
workspace (:class:`AutoWorkspace`) carries the current mode:

- **Explicit mode** (DOPRI5). After every step, Hairer's stiffness estimate
  ``h rho`` with ``rho = |k7 - k6| / |y7 - y6|`` from the two stages at ``c = 1``
  (Hairer, Norsett, Wanner I, Sec. IV.2 and ``dopri5.f``). An accepted step with
  ``h rho >`` :data:`STIFF_HRHO` counts as stiff; :data:`TO_STIFF_AFTER` of them
  switch to the Rosenbrock method, and :data:`RESET_AFTER` consecutive
  non-stiff steps clear the count (hysteresis). Hairer's estimate is a secant
  through the stages, and in the stick band of the regularised friction law it can
  miss the stiffness: the explicit method then chatters about the band with steps
  held far below the Rosenbrock method's (measured: 20 million steps where Rodas5P
  takes 1 159). Two more tests catch that. Every :data:`PROBE_EVERY`-th accepted
  explicit step takes one power iteration on the Jacobian itself (one more f, the
  same estimate as in stiff mode); ``h rho > STIFF_HRHO`` by it switches at once.
  And :data:`TO_STIFF_BUSY` accepted steps with Hairer's ``h rho >``
  :data:`BUSY_HRHO` (a step below it halves the count) switch too: steps that keep
  a sizable fraction of the stability bound are held there by the fast mode, not by
  accuracy. Where that was wrong, the stiff mode's own test switches back. An
  explicit stretch shorter than :data:`SHORT_RUN` steps doubles a hold (1, 2, 4, ...,
  up to :data:`MAX_HOLD`), and the next stiff stretch needs as many calm steps, at
  least :data:`TO_EXPLICIT_AFTER`, before it may switch back: with a
  disk stuck and another sliding fast, the stiff mode's first steps are tiny, pass the
  calm test, and the run would switch to and fro every few steps.
- **Stiff mode** (Rodas5P, the same stages as ``method="rodas5p"``). After every
  accepted step one power iteration on the Jacobian by a finite difference of
  f (one more f evaluation, warm-started, so it converges over the steps) gives
  ``rho``; :data:`TO_EXPLICIT_AFTER` consecutive accepted steps with
  ``h rho <`` :data:`EXPLICIT_HRHO` (well inside DOPRI5's stability region)
  switch back.

The switch happens between steps, after the observer has seen the step: the
new method starts from the accepted state with f(y) already known (DOPRI5's
FSAL stage, or Rodas5P's f0), and the step-size controller carries on (both
methods have q = 5). The dense output of both is returned in the Rosenbrock's
Hermite form (DOPRI5's polynomial continuous extension rewritten exactly, see
:func:`_erk_dense_hermite`), so the observer sees one kind and every step's
interpolant runs from its y0 to its y1: the trajectory the section and the
samples see is continuous across a switch.

Statistics (the last :data:`N_AUTO_STATS` slots of the workspace's ``flags``,
which :func:`.trajectory._run` copies out): switches to stiff and to explicit,
the accepted steps of each method and the attempted steps of each (accepted and
rejected). Nothing here is compiled unless a run asks for
"auto" (its records are types of their own).
"""

from __future__ import annotations

import math
from collections import namedtuple

import numpy as np
from numba.extending import overload

from ..base.jit import JIT, OVERLOAD, is_record, njit, overload_call
from .problems import problem_f
from .steppers import (
    DENSE_HERMITE,
    DOPRI5_METHOD,
    RODAS5P_METHOD,
    alloc_workspace,
    erk_accept,
    erk_init,
    erk_step,
    ros_step,
    stepper_accept,
    stepper_dense,
    stepper_dense_kind,
    stepper_init,
    stepper_step,
)

__all__ = [
    "AutoMethod",
    "AutoWorkspace",
    "AUTO_METHOD",
    "auto_method",
    "AUTO_STATS",
    "N_AUTO_STATS",
    "STIFF_HRHO",
    "TO_STIFF_AFTER",
    "RESET_AFTER",
    "EXPLICIT_HRHO",
    "TO_EXPLICIT_AFTER",
    "BUSY_HRHO",
    "TO_STIFF_BUSY",
    "PROBE_EVERY",
    "SHORT_RUN",
    "MAX_HOLD",
    "N_AUTO_FLAGS",
]

_JIT = JIT
_OVL = OVERLOAD

#: The switching method: an explicit record, a Rosenbrock record, the controller's
#: q, and the switching rule's thresholds (see the module docstring and the
#: constants below, which are the values of :data:`AUTO_METHOD`).
AutoMethod = namedtuple(
    "AutoMethod",
    ["erk", "ros", "q", "stiff_hrho", "to_stiff_after", "reset_after", "explicit_hrho",
     "to_explicit_after", "busy_hrho", "to_stiff_busy", "probe_every", "short_run",
     "max_hold"],
)  # fmt: skip

#: DOPRI5's stability boundary on the negative real axis (Hairer's test value).
STIFF_HRHO = 3.25
#: Stiff-flagged accepted explicit steps that switch to the Rosenbrock method.
TO_STIFF_AFTER = 3
#: Consecutive non-stiff explicit steps that clear the stiff count.
RESET_AFTER = 6
#: h rho below which the explicit method is taken to be stable (a margin below 3.25).
EXPLICIT_HRHO = 1.5
#: Consecutive accepted Rosenbrock steps with h rho below EXPLICIT_HRHO that switch back.
TO_EXPLICIT_AFTER = 4
#: h rho (Hairer's estimate) above which an explicit step counts as held by the fast mode.
BUSY_HRHO = 0.5
#: Such accepted explicit steps that switch to the Rosenbrock method (a step at or
#: below BUSY_HRHO halves the count).
TO_STIFF_BUSY = 50
#: Every this many accepted explicit steps, one power iteration on the Jacobian.
PROBE_EVERY = 4
#: An explicit stretch shorter than this many accepted steps doubles a hold (1, 2, 4, ...)
#: and a longer one clears it; a stiff stretch needs max(TO_EXPLICIT_AFTER, hold) calm
#: steps before it may switch back. It stops a run switching to and fro every few steps.
SHORT_RUN = 8
#: The largest hold.
MAX_HOLD = 1024


def auto_method(
    stiff_hrho: float = STIFF_HRHO,
    to_stiff_after: int = TO_STIFF_AFTER,
    reset_after: int = RESET_AFTER,
    explicit_hrho: float = EXPLICIT_HRHO,
    to_explicit_after: int = TO_EXPLICIT_AFTER,
    busy_hrho: float = BUSY_HRHO,
    to_stiff_busy: int = TO_STIFF_BUSY,
    probe_every: int = PROBE_EVERY,
    short_run: int = SHORT_RUN,
    max_hold: int = MAX_HOLD,
) -> AutoMethod:
    """The switching method record (DOPRI5 and Rodas5P) with the given thresholds."""
    return AutoMethod(
        DOPRI5_METHOD, RODAS5P_METHOD, 5.0, float(stiff_hrho), int(to_stiff_after),
        int(reset_after), float(explicit_hrho), int(to_explicit_after), float(busy_hrho),
        int(to_stiff_busy), int(probe_every), int(short_run), int(max_hold),
    )  # fmt: skip


#: ``method="auto"``.
AUTO_METHOD = auto_method()
assert DOPRI5_METHOD.q == RODAS5P_METHOD.q == AUTO_METHOD.q
# the Hermite form of DOPRI5's quartic extension has 3 rows, as Rodas5P's
assert DOPRI5_METHOD.P.shape[0] - 1 == RODAS5P_METHOD.H.shape[0]

# slots of AutoWorkspace.flags (slot 0: the Jacobian is fresh, as in StepWorkspace)
(A_MODE, A_N_STIFF, A_N_CALM, A_N_BUSY, A_RUN, A_HOLD, A_TO_STIFF, A_TO_EXPLICIT,
 A_STEPS_ERK, A_STEPS_ROS, A_TRIES_ERK, A_TRIES_ROS) = range(1, 13)  # fmt: skip
#: Size of AutoWorkspace.flags; the statistics are its last N_AUTO_STATS slots
#: (read by :func:`.trajectory._run` on any workspace whose flags are this long).
N_AUTO_FLAGS = 13
# slots of AutoWorkspace.fst
A_H, A_HRHO = range(2)
#: The statistics, in order (``flags[A_TO_STIFF:]``).
AUTO_STATS = (
    "to_stiff", "to_explicit", "steps_explicit", "steps_rosenbrock", "attempts_explicit",
    "attempts_rosenbrock",
)  # fmt: skip
N_AUTO_STATS = len(AUTO_STATS)

#: The workspace: :class:`~.steppers.StepWorkspace`'s fields (K with the larger
#: stage count; ``flags`` with the mode, counters and statistics after the
#: Jacobian flag) and ``y6`` (DOPRI5's sixth stage argument), ``v``/``fv`` (the
#: power iteration's vector and scratch) and ``fst`` (last h, last h rho).
AutoWorkspace = namedtuple(
    "AutoWorkspace",
    ["K", "ytmp", "ftmp", "f0", "ynew", "err", "D", "flags", "y6", "v", "fv", "fst"],
)

_is = is_record


@njit(**_JIT)
def _alloc_auto(stages: int, dense_rows: int, n: int) -> AutoWorkspace:
    v = np.full(n, 1.0 / math.sqrt(n))
    return AutoWorkspace(
        np.zeros((stages, n)), np.zeros(n), np.zeros(n), np.zeros(n), np.zeros(n), np.zeros(n),
        np.zeros((dense_rows, n)), np.zeros(N_AUTO_FLAGS, dtype=np.int64), np.zeros(n), v,
        np.zeros(n), np.zeros(2),
    )  # fmt: skip


@overload(alloc_workspace, **_OVL)
def _auto_alloc_workspace(method, n):
    if _is(method, AutoMethod):
        return lambda method, n: _alloc_auto(
            max(method.erk.b.size, method.ros.b.size), method.ros.H.shape[0], n
        )


@njit(inline="always", **_JIT)
def _erk_step_rho(A, b, b_err, prob, y0, h, K, ytmp, y1, err, y6) -> float:
    """:func:`.steppers.erk_step`, then the sixth stage's argument into ``y6`` and Hairer's
    stiffness estimate h |k7 - k6| / |y1 - y6|.

    ``y6`` is formed again from the stages, in the order the step formed it, so it is
    the step's own argument to the last bit (and the step keeps one stage loop).
    """
    erk_step(A, b, b_err, prob, y0, h, K, ytmp, y1, err)
    s = b.size
    st = s - 2
    num = 0.0
    den = 0.0
    for i in range(y0.size):
        acc = 0.0
        for j in range(st):
            acc += A[st, j] * K[j, i]
        y6[i] = y0[i] + h * acc
        dk = K[s - 1, i] - K[st, i]
        dy = y1[i] - y6[i]
        num += dk * dk
        den += dy * dy
    if den > 0.0:
        return h * math.sqrt(num / den)
    return 0.0


@njit(inline="always", **_JIT)
def _power_step(prob, y, f0, v, ytmp, fv) -> float:
    """One power iteration on J(y) by a forward difference of f: |J v| for |v| = 1; v <- J v / |J v|."""
    n = y.size
    ny = 0.0
    for i in range(n):
        ny += y[i] * y[i]
    delta = 1e-7 * (1.0 + math.sqrt(ny))
    for i in range(n):
        ytmp[i] = y[i] + delta * v[i]
    problem_f(prob, ytmp, fv)
    norm = 0.0
    for i in range(n):
        fv[i] = (fv[i] - f0[i]) / delta
        norm += fv[i] * fv[i]
    norm = math.sqrt(norm)
    if norm > 0.0 and math.isfinite(norm):
        for i in range(n):
            v[i] = fv[i] / norm
        return norm
    for i in range(n):  # restart from the diagonal
        v[i] = 1.0 / math.sqrt(n)
    return 0.0 if norm == 0.0 else math.inf


@njit(inline="always", **_JIT)
def _stiff_direction(y1, y6, v) -> None:
    """``v`` <- the unit vector along ``y1 - y6`` (the diagonal where they agree)."""
    n = v.size
    nv = 0.0
    for i in range(n):
        v[i] = y1[i] - y6[i]
        nv += v[i] * v[i]
    nv = math.sqrt(nv)
    for i in range(n):
        v[i] = v[i] / nv if nv > 0.0 else 1.0 / math.sqrt(n)


@njit(inline="always", **_JIT)
def _switch_mode(ist, mode, count_slot) -> None:
    """Enter ``mode`` (0 explicit, 1 Rosenbrock): count the switch, clear both step counts."""
    ist[A_MODE] = mode
    ist[count_slot] += 1
    ist[A_N_STIFF] = 0
    ist[A_N_CALM] = 0
    ist[A_N_BUSY] = 0
    ist[A_RUN] = 0


@overload_call(stepper_init)
def _auto_init(method, prob, lin, y, ws):
    if _is(method, AutoMethod):

        def impl(method, prob, lin, y, ws):
            erk_init(prob, y, ws)
            for k in range(ws.flags.size):
                ws.flags[k] = 0  # Jacobian stale, explicit mode, no counts
            ws.fst[A_H] = 0.0
            ws.fst[A_HRHO] = 0.0

        return impl


@overload_call(stepper_step)
def _auto_step(method, prob, lin, y, h, ws):
    if _is(method, AutoMethod):

        def impl(method, prob, lin, y, h, ws):
            ws.fst[A_H] = h
            if ws.flags[A_MODE] == 0:
                ws.flags[A_TRIES_ERK] += 1
                e = method.erk
                ws.fst[A_HRHO] = _erk_step_rho(
                    e.A, e.b, e.b_err, prob, y, h, ws.K, ws.ytmp, ws.ynew, ws.err, ws.y6
                )
                return True
            ws.flags[A_TRIES_ROS] += 1
            return ros_step(method.ros, prob, lin, y, h, ws)

        return impl


@overload_call(stepper_accept)
def _auto_accept(method, prob, lin, y, ws, modified):
    if _is(method, AutoMethod):

        def impl(method, prob, lin, y, ws, modified):
            n = y.size
            ist = ws.flags
            if ist[A_MODE] == 0:
                ist[A_STEPS_ERK] += 1
                ist[A_RUN] += 1
                erk_accept(method.erk, prob, y, ws, modified)
                hrho = ws.fst[A_HRHO]
                if hrho > method.stiff_hrho:
                    ist[A_N_STIFF] += 1
                    ist[A_N_CALM] = 0
                else:
                    ist[A_N_CALM] += 1
                    if ist[A_N_CALM] >= method.reset_after:
                        ist[A_N_STIFF] = 0
                if hrho > method.busy_hrho:
                    ist[A_N_BUSY] += 1
                else:
                    ist[A_N_BUSY] //= 2
                probed_stiff = False
                if ist[A_STEPS_ERK] % method.probe_every == 0:
                    # the Jacobian's own spectral radius: K[0] is f(y) (FSAL)
                    rho = _power_step(prob, y, ws.K[0], ws.v, ws.ytmp, ws.fv)
                    probed_stiff = ws.fst[A_H] * rho > method.stiff_hrho
                if (
                    probed_stiff
                    or ist[A_N_STIFF] >= method.to_stiff_after
                    or ist[A_N_BUSY] >= method.to_stiff_busy
                ):
                    # to Rodas5P: f(y) is the FSAL stage
                    if ist[A_RUN] < method.short_run:
                        ist[A_HOLD] = min(2 * max(ist[A_HOLD], 1), method.max_hold)
                    else:
                        ist[A_HOLD] = 0
                    _switch_mode(ist, 1, A_TO_STIFF)
                    ws.flags[0] = 0
                    for i in range(n):
                        ws.f0[i] = ws.K[0, i]
                    if not probed_stiff:
                        # start the power iteration on the stiff direction Hairer's
                        # estimate saw (y1 - y6); after a probe, v is already the
                        # Jacobian's own iterate and is kept
                        _stiff_direction(ws.ynew, ws.y6, ws.v)
                return
            ist[A_STEPS_ROS] += 1
            problem_f(prob, y, ws.f0)
            ws.flags[0] = 0
            rho = _power_step(prob, y, ws.f0, ws.v, ws.ytmp, ws.fv)
            if ws.fst[A_H] * rho < method.explicit_hrho:
                ist[A_N_CALM] += 1
            else:
                ist[A_N_CALM] = 0
            if ist[A_N_CALM] >= max(method.to_explicit_after, ist[A_HOLD]):
                _switch_mode(ist, 0, A_TO_EXPLICIT)
                for i in range(n):
                    ws.K[0, i] = ws.f0[i]  # DOPRI5's first stage

        return impl


@njit(inline="always", **_JIT)
def _erk_dense_hermite(P, K, h, D) -> None:
    """DOPRI5's continuous extension in the Hermite form of the Rosenbrock methods.

    With E_r = h sum_j P[r, j] k_j, y(theta) = y0 + sum_r theta^(r+1) E_r, and
    y1 = y0 + sum_r E_r, the same polynomial is (1 - theta) y0 + theta (y1 +
    (1 - theta) (D_0 + theta D_1 + theta^2 D_2)) with D_k = -sum_{r > k} E_r.
    """
    m = P.shape[0]
    s = P.shape[1]
    n = K.shape[1]
    for i in range(n):
        acc = 0.0
        for r in range(m - 1, 0, -1):
            e = 0.0
            for j in range(s):
                e += P[r, j] * K[j, i]
            acc -= h * e
            D[r - 1, i] = acc


@overload_call(stepper_dense)
def _auto_dense(method, ws, h):
    if _is(method, AutoMethod):

        def impl(method, ws, h):
            if ws.flags[A_MODE] == 0:
                _erk_dense_hermite(method.erk.P, ws.K, h, ws.D)
            else:
                H = method.ros.H
                s = H.shape[1]
                for r in range(H.shape[0]):
                    for i in range(ws.K.shape[1]):
                        acc = 0.0
                        for j in range(s):
                            acc += H[r, j] * ws.K[j, i]
                        ws.D[r, i] = acc

        return impl


@overload(stepper_dense_kind, **_OVL)
def _auto_dense_kind(method):
    if _is(method, AutoMethod):
        return lambda method: DENSE_HERMITE
