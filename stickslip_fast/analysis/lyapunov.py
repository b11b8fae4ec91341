"""Largest Lyapunov exponent from the variational equations (Benettin).

:func:`largest_lyapunov` integrates the state ``y`` together with one tangent
vector ``u`` of the variational equations, ``u' = J(y) u``: the problem
:class:`problems.StickSlipTangent` with one tangent vector, on the one adaptive
driver (:func:`driver.drive`) with the compiled Rosenbrock method Rodas5P (the
friction law is stiff while a disk sticks). The exact Jacobian of the
augmented system is

    [[J(y),  0   ],
     [H(y,u), J(y)]],      H(y, u) v = D^2 f(y)[u, v],

so each stage costs two O(N) solves with the *same* factored W plus the
bilinear form D^2 f(y)[u, v] (:func:`model.second_derivative_form`). The
:class:`LyapunovObserver` renormalises the tangent vector every ``renorm_dt``
(Benettin et al.); the exponent is the mean logarithmic growth rate after
``t_transient``.
"""

from __future__ import annotations

import math
import time
from collections import namedtuple
from dataclasses import dataclass, field

import numpy as np

from ..base.interrupt import call_interruptible, new_abort_flag
from ..base.jit import ENTRY, JIT, is_record, njit, overload_call
from ..base.messages import plain
from ..base.status import ST_ERROR, STATUS_NAMES
from ..core.driver import (
    OBS_FAIL,
    OBS_MODIFIED,
    STOP_AT_END,
    Controls,
    StopRule,
    drive,
    observe_start,
    observe_step,
    simple_stop,
    stop_now,
)
from ..core.problems import alloc_bordered_linear
from ..core.steppers import RODAS5P_METHOD, alloc_workspace
from ..core.tangent import make_tangent, tangent_variant
from ..core.trajectory import kernel_variant, variant_matches
from ..model.params import N_PARAMS
from ..model.system import System

__all__ = ["LyapunovResult", "LyapunovObserver", "largest_lyapunov", "lyapunov_kernel"]

_JIT = JIT

# renormalise early (without recording) when |u| leaves [1/_BIG, _BIG]
_BIG = 1e100

DEFAULT_LYAP_RTOL = 1e-8
DEFAULT_LYAP_ATOL = 1e-10

#: Renormalises the tangent vector (state slots n..2n) and records the running
#: estimate. ``fs`` = (log-growth sum, t_start, next renormalisation),
#: ``flags`` = (started, records).
LyapunovObserver = namedtuple(
    "LyapunovObserver",
    ["n", "t_transient", "t_end", "renorm_dt", "conv_t", "conv_est", "fs", "flags"],
)


_is = is_record


@njit(**_JIT)
def _norm(u: np.ndarray) -> float:
    acc = 0.0
    for i in range(u.size):
        acc += u[i] * u[i]
    return math.sqrt(acc)


@overload_call(observe_start)
def _lyap_start(obs, y):
    if _is(obs, LyapunovObserver):

        def impl(obs, y):
            u = y[obs.n : 2 * obs.n]
            un = _norm(u)
            for i in range(u.size):
                u[i] /= un
            obs.fs[0] = 0.0
            obs.fs[1] = obs.t_transient
            obs.fs[2] = obs.t_transient
            obs.flags[0] = 0
            obs.flags[1] = 0
            if obs.t_transient <= 0.0:
                obs.flags[0] = 1
                obs.fs[1] = 0.0
                obs.fs[2] = obs.renorm_dt

        return impl


@overload_call(observe_step)
def _lyap_step(obs, method, ws, t0, h, y0, y1):
    if _is(obs, LyapunovObserver):

        def impl(obs, method, ws, t0, h, y0, y1):
            t = t0 + h
            u = y1[obs.n : 2 * obs.n]
            un = _norm(u)
            if not (math.isfinite(un) and un > 0.0):
                return OBS_FAIL
            if obs.flags[0] == 0:
                # before the averaging window only the direction of u matters
                for i in range(u.size):
                    u[i] /= un
                if t >= obs.t_transient:
                    obs.flags[0] = 1
                    obs.fs[1] = t
                    obs.fs[2] = t + obs.renorm_dt
            elif t >= obs.fs[2] or t >= obs.t_end:
                obs.fs[0] += math.log(un)
                for i in range(u.size):
                    u[i] /= un
                obs.fs[2] = t + obs.renorm_dt
                k = obs.flags[1]
                if k < obs.conv_t.shape[0]:
                    obs.conv_t[k] = t
                    obs.conv_est[k] = obs.fs[0] / (t - obs.fs[1])
                    obs.flags[1] = k + 1
            elif un > _BIG or un < 1.0 / _BIG:
                obs.fs[0] += math.log(un)
                for i in range(u.size):
                    u[i] /= un
            return OBS_MODIFIED

        return impl


@overload_call(stop_now)
def _lyap_stop(stop, obs, t, y):
    if _is(stop, StopRule) and _is(obs, LyapunovObserver):
        return lambda stop, obs, t, y: False


@njit(**ENTRY)
def lyapunov_kernel(
    y0: np.ndarray,
    u0: np.ndarray,
    p: np.ndarray,
    n_osc: int,
    dc: bool,
    variant: tuple,
    t_end: float,
    t_transient: float,
    rtol: float,
    atol: float,
    tangent_atol: float,
    renorm_dt: float,
    max_steps: int,
    conv_t: np.ndarray,
    conv_est: np.ndarray,
    y_end: np.ndarray,
    stats: np.ndarray,
    fstats: np.ndarray,
    abort: np.ndarray,
) -> int:
    """Benettin's algorithm for the largest Lyapunov exponent; returns a status code.

    Integrates (y, u) from t = 0 to ``t_end`` with adaptive Rodas5P on the
    driver. The error norm is the RMS over both parts, y scaled by atol +
    rtol |y| and u by tangent_atol |u_0| + rtol |u| (u is a direction: its
    absolute tolerance is relative to its current length). The tangent vector
    is renormalised at the first step end at or after t_transient (where the
    averaging starts), then at step ends at least ``renorm_dt`` apart,
    recording (t, running estimate) into ``conv_t``/``conv_est``. Outputs:
    ``stats`` = (steps, rejected, records), ``fstats`` = (exponent, t_start,
    t_final, log-growth sum), ``y_end``. ``variant`` selects the kernel as in
    :func:`~stickslip_fast.core.variational.propagate_tangents`.
    """
    n = y0.size
    fstats[0] = math.nan
    if not variant_matches(variant, n_osc, dc):
        return ST_ERROR
    prob = tangent_variant(make_tangent(p, n_osc, dc, 1, tangent_atol, np.empty(N_PARAMS)), variant)
    y = np.empty(2 * n)
    for i in range(n):
        y[i] = y0[i]
        y[n + i] = u0[i]
    obs = LyapunovObserver(
        n, t_transient, t_end, renorm_dt, conv_t, conv_est, np.zeros(3), np.zeros(2, dtype=np.int64)
    )
    istat = np.zeros(2, dtype=np.int64)
    fstat = np.zeros(1)
    status = drive(
        RODAS5P_METHOD, prob, alloc_bordered_linear(n_osc, 2 * n),
        alloc_workspace(RODAS5P_METHOD, 2 * n), y, t_end,
        Controls(rtol, atol, 0.0, max_steps), obs, simple_stop(STOP_AT_END, 0, 0), abort, istat, fstat,
    )  # fmt: skip
    for i in range(n):
        y_end[i] = y[i]
    t = fstat[0]
    t_start = obs.fs[1]
    stats[0] = istat[0]
    stats[1] = istat[1]
    stats[2] = obs.flags[1]
    fstats[1] = t_start
    fstats[2] = t
    fstats[3] = obs.fs[0]
    if obs.flags[0] != 0 and t > t_start:
        fstats[0] = obs.fs[0] / (t - t_start)
    else:
        fstats[0] = math.nan
    return status


# ----------------------------------------------------------------------- public API
@dataclass
class LyapunovResult:
    """What :func:`largest_lyapunov` returns.

    Attributes
    ----------
    exponent : float
        Largest Lyapunov exponent (Benettin): ``log(|u(t_final)| / |u(t_start)|)``
        / (t_final - t_start), NaN if the run failed before t_transient.
    exponent_fit : float
        Least-squares slope of the cumulative log growth L(t) over the
        convergence records. Same limit; for a periodic orbit the bounded
        periodic part of L biases it only by O(1 / T^2) instead of O(1 / T).
    convergence : ndarray, shape (k, 2)
        Columns (t, running estimate) at each renormalisation after t_transient.
    status : str
        "ok", "nonfinite", "step-underflow" or "max-steps".
    t_start, t_final : float
        Averaging window (t_start is the first step end at or after t_transient).
    n_steps, n_rejected : int
        Accepted and rejected steps of the augmented system.
    final_state : ndarray
        State y at t_final.
    runtime : float
        Wall-clock seconds of the compiled kernel.
    settings : dict
    """

    exponent: float
    exponent_fit: float
    convergence: np.ndarray
    status: str
    t_start: float
    t_final: float
    n_steps: int
    n_rejected: int
    final_state: np.ndarray
    runtime: float
    settings: dict = field(default_factory=dict)

    def __repr__(self) -> str:
        return (
            f"LyapunovResult(exponent={self.exponent:.6g}, exponent_fit={self.exponent_fit:.6g}, "
            f"status={self.status!r}, "
            f"n_steps={self.n_steps}, runtime={self.runtime:.3g}s)"
        )


def largest_lyapunov(
    system: System,
    t_end: float,
    t_transient: float = 0.0,
    y0: np.ndarray | list | None = None,
    rtol: float = DEFAULT_LYAP_RTOL,
    atol: float = DEFAULT_LYAP_ATOL,
    renorm_dt: float = 1.0,
    *,
    u0: np.ndarray | list | None = None,
    tangent_atol: float = 1e-8,
    max_steps: int = 50_000_000,
) -> LyapunovResult:
    """Largest Lyapunov exponent from the variational equations (Benettin).

    Integrates y' = f(y) and u' = J(y) u with the analytic Jacobian, using a
    compiled Rodas5P kernel on the augmented autonomous system, and averages
    the log growth of ``|u|`` over [t_transient, t_end].

    Parameters
    ----------
    system : System
    t_end : float
        Final time.
    t_transient : float
        Averaging starts at the first step end at or after this time; before it
        only the direction of u evolves.
    y0 : array_like, optional
        Initial state (default zeros, as in :func:`stickslip_fast.simulate`).
    rtol, atol : float
        Tolerances of the y part (defaults 1e-8 and 1e-10, as ``simulate``).
    renorm_dt : float
        Minimum time between renormalisations (and convergence records).
    u0 : array_like, optional
        Initial tangent vector; default a fixed pseudo-random unit vector
        (seed 12345), which has components along every direction.
    tangent_atol : float
        Absolute tolerance of the tangent part relative to ``|u|`` (default 1e-8:
        on the presets the exponent agrees with 1e-10 to ~1e-6 at a third fewer
        steps).
    max_steps : int
        Give up with status "max-steps" after this many accepted steps.

    Returns
    -------
    LyapunovResult

    Notes
    -----
    For a periodic orbit of an autonomous system the largest exponent is 0
    (the flow direction neither grows nor shrinks on average); the finite-time
    estimate carries a bias of order ``log(|f(y_end)| / |f(y_start)|)`` / (t_end -
    t_start), which decays like 1 / t_end.

    Examples
    --------
    >>> from stickslip_fast import System
    >>> res = largest_lyapunov(System.preset("symmetric", eta=5.0), 6000, 1000)
    >>> abs(res.exponent) < 1e-3  # doctest: +SKIP
    True
    """
    y_init, u_init, tangent_atol = _lyapunov_inputs(
        system, t_end, t_transient, y0, rtol, atol, renorm_dt, u0, tangent_atol
    )
    return _run_lyapunov(
        system, y_init, u_init, t_end, t_transient, rtol, atol, tangent_atol, renorm_dt, max_steps
    )


def _lyapunov_inputs(system, t_end, t_transient, y0, rtol, atol, renorm_dt, u0, tangent_atol):
    """Check :func:`largest_lyapunov`'s arguments; the initial state, tangent vector and
    ``tangent_atol`` as the kernel takes them."""
    if not isinstance(system, System):
        raise TypeError(f"system must be a stickslip_fast.System, got {type(system).__name__}")
    for name, value in (("t_end", t_end), ("rtol", rtol), ("atol", atol), ("renorm_dt", renorm_dt)):
        if not (math.isfinite(value) and value > 0):
            raise ValueError(f"{name} must be finite and > 0, got {plain(value)}")
    if not (math.isfinite(t_transient) and 0 <= t_transient < t_end):
        raise ValueError(f"t_transient must be in [0, t_end), got {plain(t_transient)}")
    tangent_atol = float(tangent_atol)
    if not (math.isfinite(tangent_atol) and tangent_atol > 0):
        raise ValueError(f"tangent_atol must be finite and > 0, got {plain(tangent_atol)}")
    y_init = system.initial_state(y0)
    n = system.n_state
    if u0 is None:
        u_init = np.random.default_rng(12345).standard_normal(n)
    else:
        u_init = np.asarray(u0, dtype=float)
        if u_init.shape != (n,) or not np.all(np.isfinite(u_init)) or not np.any(u_init):
            raise ValueError(f"u0 must be a finite nonzero vector of length {n}")
    return y_init, u_init, tangent_atol


def _fit_slope(conv: np.ndarray, t_start: float) -> float:
    """Least-squares slope of the accumulated log growth against time (NaN below 2 records)."""
    k = len(conv)
    if k >= 2:
        tt = np.concatenate([[t_start], conv[:, 0]])
        growth = np.concatenate([[0.0], conv[:, 1] * (conv[:, 0] - t_start)])
        slope = float(np.polyfit(tt, growth, 1)[0])
    else:
        slope = math.nan
    return slope


def _run_lyapunov(
    system, y_init, u_init, t_end, t_transient, rtol, atol, tangent_atol, renorm_dt, max_steps
) -> LyapunovResult:
    """Run the compiled kernel on checked inputs and collect its :class:`LyapunovResult`."""
    cap = int((t_end - t_transient) / renorm_dt) + 2
    conv_t = np.empty(cap)
    conv_est = np.empty(cap)
    y_end = np.empty(system.n_state)
    stats = np.zeros(3, dtype=np.int64)
    fstats = np.zeros(4)
    t0 = time.perf_counter()
    abort = new_abort_flag()
    code = call_interruptible(
        lyapunov_kernel,
        y_init, u_init, system.to_array(), system.n_oscillators, system.is_dc_motor,
        kernel_variant(system.n_oscillators, system.is_dc_motor),
        float(t_end), float(t_transient), float(rtol), float(atol), tangent_atol,
        float(renorm_dt), int(max_steps), conv_t, conv_est, y_end, stats, fstats, abort=abort,
    )  # fmt: skip
    runtime = time.perf_counter() - t0
    k = int(stats[2])
    conv = np.column_stack([conv_t[:k], conv_est[:k]])
    t_start = float(fstats[1])
    slope = _fit_slope(conv, t_start)
    return LyapunovResult(
        exponent=float(fstats[0]),
        exponent_fit=slope,
        convergence=conv,
        status=STATUS_NAMES[code],
        t_start=t_start,
        t_final=float(fstats[2]),
        n_steps=int(stats[0]),
        n_rejected=int(stats[1]),
        final_state=y_end,
        runtime=runtime,
        settings=dict(
            t_end=float(t_end),
            t_transient=float(t_transient),
            rtol=float(rtol),
            atol=float(atol),
            tangent_atol=tangent_atol,
            renorm_dt=float(renorm_dt),
            max_steps=int(max_steps),
        ),
    )
