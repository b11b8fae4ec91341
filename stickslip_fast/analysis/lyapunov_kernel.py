"""Lyapunov exponents from the variational equations (Benettin, with QR).

:func:`lyapunov_kernel` integrates the state ``y`` together with k tangent
vectors ``u_1 .. u_k`` of the variational equations, ``u' = J(y) u``: the
problem :class:`problems.StickSlipTangent` with k tangent vectors, on the one
adaptive driver (:func:`driver.drive`) with the compiled Rosenbrock method
Rodas5P (the friction law is stiff while a disk sticks). The exact Jacobian of
the augmented system is block lower triangular,

    [[J(y),     0   ],
     [H(y,u_j), J(y)]],      H(y, u) v = D^2 f(y)[u, v],

so each stage costs 1 + k O(N) solves with the *same* factored W plus k
evaluations of the bilinear form D^2 f(y)[u, v]
(:func:`model.second_derivative_form`). The :class:`LyapunovObserver`
re-orthonormalises the vectors after every step (Gram-Schmidt, the QR method of
Benettin et al. and Shimada and Nagashima; one vector only every ``renorm_dt``);
exponent j is the mean logarithmic growth rate of the j-th diagonal entry of R
after ``t_transient``.
With k = 1 this is Benettin's largest exponent
(:func:`~.lyapunov.largest_lyapunov`); :func:`~.lyapunov.lyapunov_spectrum`
takes k up to the state's size.
"""

from __future__ import annotations

import math
import time
from collections import namedtuple
from dataclasses import dataclass

import numpy as np

from ..base.interrupt import call_interruptible, new_abort_flag
from ..base.jit import ENTRY, JIT, is_record, njit, overload_call
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
from ..model.equations import jacobian_blocks
from ..model.params import N_PARAMS

__all__ = ["LyapunovObserver", "lyapunov_kernel", "TangentRun", "run_tangents"]

_JIT = JIT

# one vector is renormalised early (without recording) when |u| leaves [1/_BIG, _BIG];
# k > 1 vectors are re-orthonormalised after every step (see _lyap_step)
_BIG = 1e100
# a vector shorter than this after Gram-Schmidt has vanished (is replaced)
_TINY = 1e-290

#: Re-orthonormalises the k tangent vectors (state slots n..(1 + k) n) and
#: records the running estimates. ``logs`` = the k log-growth sums, ``fs`` =
#: (t_start, next renormalisation, trace J at the last step end, integral of
#: trace J over the window), ``flags`` = (started, records). ``p``, ``n_osc``,
#: ``dc``, ``jb``, ``jcol``, ``jrow``: the model and scratch for the trace.
#: ``vanished``: for each vector, how often in the window it shrank below
#: :data:`_TINY` between two orthonormalisations and was replaced.
LyapunovObserver = namedtuple(
    "LyapunovObserver",
    ["n", "k", "t_transient", "t_end", "renorm_dt", "conv_t", "conv_est", "logs", "fs", "flags",
     "p", "n_osc", "dc", "jb", "jcol", "jrow", "vanished"],
)  # fmt: skip


_is = is_record


@njit(**_JIT)
def _norm(u: np.ndarray) -> float:
    acc = 0.0
    for i in range(u.size):
        acc += u[i] * u[i]
    return math.sqrt(acc)


@njit(**_JIT)
def _project_out(y: np.ndarray, n: int, j: int) -> None:
    """Vector j loses its projections on vectors 0 .. j-1 (orthonormal), twice: modified
    Gram-Schmidt repeated ("twice is enough") keeps the frame orthonormal to rounding
    even where the vectors have drawn close."""
    u = y[n * (1 + j) : n * (2 + j)]
    for _ in range(2 if j > 0 else 0):
        for m in range(j):
            q = y[n * (1 + m) : n * (2 + m)]
            d = 0.0
            for i in range(n):
                d += q[i] * u[i]
            for i in range(n):
                u[i] -= d * q[i]


@njit(**_JIT)
def _replace_vanished(y: np.ndarray, n: int, j: int) -> None:
    """Vector j (nothing left of it) replaced by the unit vector along the coordinate that
    vectors 0 .. j-1 cover least, before it loses its projections on them."""
    best = 0
    least = math.inf
    for i in range(n):
        cover = 0.0
        for m in range(j):
            q = y[n * (1 + m) + i]
            cover += q * q
        if cover < least:
            least = cover
            best = i
    u = y[n * (1 + j) : n * (2 + j)]
    for i in range(n):
        u[i] = 1.0 if i == best else 0.0
    _project_out(y, n, j)


@njit(**_JIT)
def _orthonormalise(
    y: np.ndarray, n: int, k: int, logs: np.ndarray, vanished: np.ndarray, accumulate: bool
) -> bool:
    """Gram-Schmidt on the k vectors y[n (1 + j) : n (2 + j)], in place; False if one is
    not finite.

    Each vector loses its projections on the ones before it (:func:`_project_out`),
    then is normalised; with ``accumulate`` the log of its norm, R's diagonal, is
    added to ``logs``. A vector with nothing left (a stick phase can crush a
    direction below the smallest float within a step) is replaced by a fresh one
    and counted as shrunk to :data:`_TINY` (and in ``vanished``). For k = 1 this is exactly the
    normalisation of one vector.
    """
    for j in range(k):
        _project_out(y, n, j)
        u = y[n * (1 + j) : n * (2 + j)]
        un = _norm(u)
        if not math.isfinite(un):
            return False
        if not un > _TINY:
            _replace_vanished(y, n, j)
            if accumulate:
                logs[j] += math.log(_TINY)
                vanished[j] += 1
            un = _norm(u)
        elif accumulate:
            logs[j] += math.log(un)
        for i in range(n):
            u[i] /= un
    return True


@njit(**_JIT)
def _trace(y, p, n_osc, dc, jb, jcol, jrow) -> float:
    """The divergence of the vector field at y: the trace of the model's Jacobian."""
    corner = jacobian_blocks(y, p, n_osc, dc, jb, jcol, jrow)
    acc = corner if dc else 0.0
    for i in range(n_osc):
        for r in range(4):
            acc += jb[i, r, r]
    return acc


@njit(inline="always", **_JIT)
def _divergence_at(obs, y) -> float:
    return _trace(y[: obs.n], obs.p, obs.n_osc, obs.dc, obs.jb, obs.jcol, obs.jrow)


@overload_call(observe_start)
def _lyap_start(obs, y):
    if _is(obs, LyapunovObserver):

        def impl(obs, y):
            _orthonormalise(y, obs.n, obs.k, obs.logs, obs.vanished, False)
            for j in range(obs.k):
                obs.logs[j] = 0.0
            obs.fs[0] = obs.t_transient
            obs.fs[1] = obs.t_transient
            obs.fs[3] = 0.0
            obs.flags[0] = 0
            obs.flags[1] = 0
            if obs.t_transient <= 0.0:
                obs.flags[0] = 1
                obs.fs[0] = 0.0
                obs.fs[1] = obs.renorm_dt
                obs.fs[2] = _divergence_at(obs, y)

        return impl


@njit(**_JIT)
def _norm_check(u: np.ndarray) -> int:
    """One vector: 0 if it may go on; 1 if it needs renormalising now (its norm out of
    [1/_BIG, _BIG]); 2 if its norm is not finite."""
    un = _norm(u)
    if not math.isfinite(un):
        return 2
    return 1 if (un > _BIG or un < 1.0 / _BIG) else 0


@overload_call(observe_step)
def _lyap_step(obs, method, ws, t0, h, y0, y1):
    if _is(obs, LyapunovObserver):

        def impl(obs, method, ws, t0, h, y0, y1):
            t = t0 + h
            if obs.flags[0] != 0:
                # the divergence's integral over the window (trapezoid over the steps)
                tr = _divergence_at(obs, y1)
                obs.fs[3] += 0.5 * h * (obs.fs[2] + tr)
                obs.fs[2] = tr
            if obs.flags[0] == 0:
                # before the averaging window only the directions of the u_j matter
                if not _orthonormalise(y1, obs.n, obs.k, obs.logs, obs.vanished, False):
                    return OBS_FAIL
                if t >= obs.t_transient:
                    obs.flags[0] = 1
                    obs.fs[0] = t
                    obs.fs[1] = t + obs.renorm_dt
                    obs.fs[2] = _divergence_at(obs, y1)
            elif t >= obs.fs[1] or t >= obs.t_end:
                if not _orthonormalise(y1, obs.n, obs.k, obs.logs, obs.vanished, True):
                    return OBS_FAIL
                obs.fs[1] = t + obs.renorm_dt
                r = obs.flags[1]
                if r < obs.conv_t.shape[0]:
                    obs.conv_t[r] = t
                    for j in range(obs.k):
                        obs.conv_est[r, j] = obs.logs[j] / (t - obs.fs[0])
                    obs.flags[1] = r + 1
            elif obs.k > 1:
                # every step: where a stick phase contracts two directions at rates of
                # thousands, vectors left alone for a few steps fold onto each other
                # (their lengths stay alike) and the faster one's digits are lost
                if not _orthonormalise(y1, obs.n, obs.k, obs.logs, obs.vanished, True):
                    return OBS_FAIL
            else:
                check = _norm_check(y1[obs.n : 2 * obs.n])
                if check == 2:
                    return OBS_FAIL
                if check == 0:
                    return 0
                _orthonormalise(y1, obs.n, obs.k, obs.logs, obs.vanished, True)
            return OBS_MODIFIED

        return impl


@overload_call(stop_now)
def _lyap_stop(stop, obs, t, y):
    if _is(stop, StopRule) and _is(obs, LyapunovObserver):
        return lambda stop, obs, t, y: False


@njit(**ENTRY)
def lyapunov_kernel(
    y0: np.ndarray,
    frame: np.ndarray,
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
    logs: np.ndarray,
    vanished: np.ndarray,
    abort: np.ndarray,
) -> int:
    """Benettin's algorithm with k tangent vectors; returns a status code.

    Integrates (y, u_1 .. u_k) from t = 0 to ``t_end`` with adaptive Rodas5P on
    the driver; the u_j start as the rows of ``frame`` (k, n), orthonormalised.
    The error norm is the RMS over all parts, y scaled by atol + rtol |y| and
    u_j by tangent_atol |u_j(t0)| + rtol |u_j| (the u_j are directions: their
    absolute tolerance is relative to their current length). The vectors are
    re-orthonormalised at the first step end at or after t_transient (where the
    averaging starts), then at step ends at least ``renorm_dt`` apart, recording
    (t, running estimates) into ``conv_t``/``conv_est`` (records, k); in between,
    without a record, after every step for k > 1, and for k = 1 when the norm
    leaves [1e-100, 1e100].

    Outputs: ``logs`` (the k log-growth sums); ``vanished`` (for each vector, how
    often in the window it shrank below the float range between two
    orthonormalisations); ``stats`` = (steps, rejected, records); ``fstats`` =
    (t_start, t_final, 1 if the averaging started else 0, the integral of the
    divergence trace J(y) over the window by the trapezoid rule on the steps);
    ``y_end``. ``variant`` selects the kernel as in
    :func:`~stickslip_fast.core.variational.propagate_tangents`.
    """
    n = y0.size
    k = frame.shape[0]
    for j in range(k):
        logs[j] = 0.0
        vanished[j] = 0
    fstats[0] = t_transient
    fstats[1] = 0.0
    fstats[2] = 0.0
    fstats[3] = math.nan
    if not variant_matches(variant, n_osc, dc):
        return ST_ERROR
    prob = tangent_variant(make_tangent(p, n_osc, dc, k, tangent_atol, np.empty(N_PARAMS)), variant)
    m = (1 + k) * n
    y = np.empty(m)
    for i in range(n):
        y[i] = y0[i]
    for j in range(k):
        for i in range(n):
            y[n * (1 + j) + i] = frame[j, i]
    obs = LyapunovObserver(
        n, k, t_transient, t_end, renorm_dt, conv_t, conv_est, logs, np.zeros(4),
        np.zeros(2, dtype=np.int64), prob.p, n_osc, dc, np.zeros((n_osc, 4, 4)),
        np.zeros((n_osc, 4)), np.zeros((n_osc, 4)), vanished,
    )  # fmt: skip
    istat = np.zeros(2, dtype=np.int64)
    fstat = np.zeros(1)
    status = drive(
        RODAS5P_METHOD, prob, alloc_bordered_linear(n_osc, m), alloc_workspace(RODAS5P_METHOD, m),
        y, t_end, Controls(rtol, atol, 0.0, max_steps), obs, simple_stop(STOP_AT_END, 0, 0),
        abort, istat, fstat,
    )  # fmt: skip
    for i in range(n):
        y_end[i] = y[i]
    stats[0] = istat[0]
    stats[1] = istat[1]
    stats[2] = obs.flags[1]
    fstats[0] = obs.fs[0]
    fstats[1] = fstat[0]
    fstats[2] = obs.flags[0]
    fstats[3] = obs.fs[3]
    return status


@dataclass
class TangentRun:
    """What one run of :func:`lyapunov_kernel` gave (the common part of the results).

    ``exponents``: the k plain Benettin averages; ``divergence``: the mean of trace
    J(y) over the window; ``vanished``: for each vector, how often in the window
    it shrank below the float range between two orthonormalisations;
    ``convergence``: (records, 1 + k), time and the k running estimates.
    """

    exponents: np.ndarray
    divergence: float
    vanished: np.ndarray
    convergence: np.ndarray
    status: str
    t_start: float
    t_final: float
    n_steps: int
    n_rejected: int
    final_state: np.ndarray
    runtime: float
    settings: dict

    def run_fields(self) -> dict:
        """The fields every Lyapunov result takes from the run as they are, by name."""
        return dict(
            status=self.status, t_start=self.t_start, t_final=self.t_final,
            n_steps=self.n_steps, n_rejected=self.n_rejected, final_state=self.final_state,
            runtime=self.runtime, settings=self.settings,
        )  # fmt: skip


def run_tangents(
    system, y_init, frame, t_end, t_transient, rtol, atol, tangent_atol, renorm_dt, max_steps
) -> TangentRun:
    """Run the compiled kernel on checked inputs: the state and the k rows of ``frame``."""
    k = frame.shape[0]
    cap = int((t_end - t_transient) / renorm_dt) + 2
    conv_t = np.empty(cap)
    conv_est = np.empty((cap, k))
    logs = np.zeros(k)
    vanished = np.zeros(k, dtype=np.int64)
    y_end = np.empty(system.n_state)
    stats = np.zeros(3, dtype=np.int64)
    fstats = np.zeros(4)
    t0 = time.perf_counter()
    abort = new_abort_flag()
    code = call_interruptible(
        lyapunov_kernel,
        y_init, np.ascontiguousarray(frame, dtype=float), system.to_array(),
        system.n_oscillators, system.is_dc_motor,
        kernel_variant(system.n_oscillators, system.is_dc_motor),
        float(t_end), float(t_transient), float(rtol), float(atol), tangent_atol,
        float(renorm_dt), int(max_steps), conv_t, conv_est, y_end, stats, fstats, logs,
        vanished, abort=abort,
    )  # fmt: skip
    runtime = time.perf_counter() - t0
    records = int(stats[2])
    t_start, t_final = float(fstats[0]), float(fstats[1])
    if fstats[2] != 0.0 and t_final > t_start:
        exponents = logs / (t_final - t_start)
        divergence = float(fstats[3]) / (t_final - t_start)
    else:
        exponents = np.full(k, math.nan)
        divergence = math.nan
    return TangentRun(
        exponents=exponents,
        divergence=divergence,
        vanished=vanished,
        convergence=np.column_stack([conv_t[:records], conv_est[:records]]),
        status=STATUS_NAMES[code],
        t_start=t_start,
        t_final=t_final,
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
