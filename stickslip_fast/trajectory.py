"""Trajectory and sweep kernels: pure compiled functions, parameters in, arrays out.

:func:`integrate` runs one trajectory with any of the three methods, records
the Poincare points inline (keeping the most recent ``max_points`` in a ring
buffer), optionally samples a uniform time grid, and classifies the run.
:func:`sweep_chunk` runs many trajectories in one ``prange`` loop. Both call
the same code, so a sweep value equals the corresponding simulate() bit for bit.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit, prange

from .integrators import (
    DENSE_HERMITE,
    DENSE_POLY,
    accepted_step_factor,
    dense_state,
    erk_dense,
    erk_step,
    error_norm,
    initial_step,
    rejected_step_factor,
    rosenbrock_dense,
    rosenbrock_step,
)
from .model import eta_prime, jacobian_blocks, rhs
from .poincare import (
    ST_MAX_STEPS,
    ST_NONFINITE,
    ST_OK,
    ST_UNDERFLOW,
    classify,
    detect_period,
    locate_upcrossing,
    motion_measure,
)
from .system import P_ETA, P_ETAP, P_VB0
from .tableaus import DOPRI5, RODAS5P

METHODS = ("rodas5p", "dopri5", "dopri5-fixed")
M_RODAS5P, M_DOPRI5, M_DOPRI5_FIXED = range(3)

# Tableaus as module constants: numba freezes them into the compiled kernels.
_RB_GAMMA = float(RODAS5P.gamma)
_RB_A = RODAS5P.a
_RB_C = RODAS5P.C
_RB_B = RODAS5P.b
_RB_E = RODAS5P.b_err
_RB_H = RODAS5P.H
_RB_Q = RODAS5P.embedded_order + 1.0
_RK_A = DOPRI5.A
_RK_B = DOPRI5.b
_RK_E = DOPRI5.b_err
_RK_P = DOPRI5.dense
_RK_Q = 5.0

_JIT = dict(cache=True, nogil=True)

# slots of the integer and float statistics arrays
I_STEPS, I_REJECTED, I_CROSSINGS, I_SAMPLES = range(4)
N_STAT_I = 4
F_T_FINAL, F_AMPLITUDE = range(2)
N_STAT_F = 2


@njit(**_JIT)
def _observe(
    kind,
    t0,
    h,
    y0,
    y1,
    D,
    t_transient,
    pts,
    tpts,
    n_cross,
    samples,
    sample_dt,
    n_samp,
    ymin,
    ymax,
):
    """Record what happened inside an accepted step [t0, t0 + h].

    Returns the updated (crossing count, sample count).
    """
    t1 = t0 + h
    n = y0.size
    # Poincare: dx1 crosses zero upwards (a local minimum of x1)
    if y0[1] < 0.0 <= y1[1]:
        theta = locate_upcrossing(kind, y0, y1, D, 1)
        tc = t0 + theta * h
        if tc >= t_transient:
            cap = pts.shape[0]
            if cap > 0:
                slot = n_cross % cap
                dense_state(kind, theta, y0, y1, D, pts[slot])
                tpts[slot] = tc
            n_cross += 1
    # uniform samples on t_transient + k * sample_dt
    n_grid = samples.shape[0]
    while n_samp < n_grid:
        ts = t_transient + n_samp * sample_dt
        if ts > t1:
            break
        theta = (ts - t0) / h
        theta = min(1.0, max(0.0, theta))
        dense_state(kind, theta, y0, y1, D, samples[n_samp])
        n_samp += 1
    # amplitude of the motion over the recording window
    if t1 >= t_transient:
        for i in range(n):
            v = y1[i]
            if v < ymin[i]:
                ymin[i] = v
            if v > ymax[i]:
                ymax[i] = v
    return n_cross, n_samp


@njit(**_JIT)
def integrate(
    method: int,
    y0: np.ndarray,
    p: np.ndarray,
    n_osc: int,
    dc: bool,
    t_end: float,
    t_transient: float,
    rtol: float,
    atol: float,
    h_fixed: float,
    max_steps: int,
    equilibrium_tol: float,
    pts: np.ndarray,
    tpts: np.ndarray,
    samples: np.ndarray,
    sample_dt: float,
    y_end: np.ndarray,
    stat_i: np.ndarray,
    stat_f: np.ndarray,
) -> int:
    """Integrate one trajectory from t = 0 to ``t_end``; return its status code.

    ``p`` is the packed parameter array (eta' is recomputed from eta here).
    Outputs: ``pts``/``tpts`` (ring buffer of the last Poincare points; see
    ``stat_i[I_CROSSINGS]`` for the total), ``samples`` (uniform grid from
    t_transient), ``y_end`` (state at the last accepted time), ``stat_i``
    (steps, rejected, crossings, samples) and ``stat_f`` (final time and the
    :func:`motion_measure` of the recording window).
    """
    n = y0.size
    p = p.copy()
    p[P_ETAP] = eta_prime(p[P_ETA])

    y = y0.copy()
    ynew = np.empty(n)
    ytmp = np.empty(n)
    ftmp = np.empty(n)
    f0 = np.empty(n)
    err = np.empty(n)
    ymin = np.full(n, np.inf)
    ymax = np.full(n, -np.inf)
    rosen = method == M_RODAS5P
    if rosen:
        stages = _RB_B.size
        D = np.empty((_RB_H.shape[0], n))
        kind = DENSE_HERMITE
        order_q = _RB_Q
    else:
        stages = _RK_B.size
        D = np.empty((_RK_P.shape[1], n))
        kind = DENSE_POLY
        order_q = _RK_Q
    K = np.empty((stages, n))
    jb = np.empty((n_osc, 4, 4))
    jcol = np.zeros((n_osc, 4))
    jrow = np.zeros((n_osc, 4))
    lu = np.empty((n_osc, 4, 4))
    piv = np.empty((n_osc, 4), dtype=np.int64)
    z = np.zeros((n_osc, 4))

    n_steps = 0
    n_rej = 0
    n_cross = 0
    n_samp = 0
    status = ST_OK
    t = 0.0

    rhs(y, p, n_osc, dc, f0)
    if not rosen:
        for i in range(n):
            K[0, i] = f0[i]  # FSAL: the first stage of the first step
    if samples.shape[0] > 0 and t_transient <= 0.0:
        for i in range(n):
            samples[0, i] = y[i]
        n_samp = 1
    if t_transient <= 0.0:
        for i in range(n):
            ymin[i] = y[i]
            ymax[i] = y[i]

    # h_fixed > 0 turns any method into a fixed-step one (convergence studies)
    adaptive = h_fixed <= 0.0
    if adaptive:
        h = initial_step(y, f0, p, n_osc, dc, rtol, atol, order_q - 1.0, ytmp, ftmp)
        h = min(h, t_end)
    else:
        h = h_fixed
    err_prev = 1.0
    last_rejected = False
    jac_fresh = False
    jcorner = 0.0

    while t < t_end:
        if n_steps >= max_steps:
            status = ST_MAX_STEPS
            break
        # land exactly on t_end; avoid a sliver of a last step
        if t + h >= t_end or (adaptive and t + 1.01 * h >= t_end):
            h = t_end - t
        if rosen:
            if not jac_fresh:
                jcorner = jacobian_blocks(y, p, n_osc, dc, jb, jcol, jrow)
                jac_fresh = True
            ok = rosenbrock_step(
                _RB_GAMMA, _RB_A, _RB_C, _RB_B, _RB_E, y, f0, h, p, n_osc, dc,
                jb, jcol, jrow, jcorner, lu, piv, z, K, ytmp, ftmp, ynew, err,
            )  # fmt: skip
        else:
            erk_step(_RK_A, _RK_B, _RK_E, y, h, p, n_osc, dc, K, ytmp, ynew, err)
            ok = True
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
            en = error_norm(err, y, ynew, rtol, atol)
            if not math.isfinite(en):
                ok = False
        if adaptive and (not ok or en > 1.0):
            n_rej += 1
            h *= rejected_step_factor(en, ok, order_q)
            last_rejected = True
            if h < 1e-14 * max(1.0, abs(t)):
                status = ST_UNDERFLOW if ok else ST_NONFINITE
                break
            continue

        # accepted; dense output only where a crossing or a sample needs it
        n_steps += 1
        if (y[1] < 0.0 <= ynew[1]) or (
            n_samp < samples.shape[0] and t_transient + n_samp * sample_dt <= t + h
        ):
            if rosen:
                rosenbrock_dense(_RB_H, K, D)
            else:
                erk_dense(_RK_P, K, h, D)
        n_cross, n_samp = _observe(
            kind, t, h, y, ynew, D, t_transient, pts, tpts, n_cross, samples, sample_dt,
            n_samp, ymin, ymax,
        )  # fmt: skip
        t = t + h
        for i in range(n):
            y[i] = ynew[i]
        if rosen:
            rhs(y, p, n_osc, dc, f0)
            jac_fresh = False
        else:
            for i in range(n):
                K[0, i] = K[stages - 1, i]
        if adaptive:
            h *= accepted_step_factor(en, err_prev, order_q, last_rejected)
            err_prev = max(en, 1e-10)
            last_rejected = False

    for i in range(n):
        y_end[i] = y[i]
    stat_i[I_STEPS] = n_steps
    stat_i[I_REJECTED] = n_rej
    stat_i[I_CROSSINGS] = n_cross
    stat_i[I_SAMPLES] = n_samp
    stat_f[F_T_FINAL] = t
    amp = motion_measure(ymin, ymax, n_osc, dc)
    stat_f[F_AMPLITUDE] = amp
    if status == ST_OK:
        vb_end = y[n - 1] if dc else 0.0
        status = classify(amp, n_cross, dc, vb_end, p[P_VB0], equilibrium_tol)
    return status


@njit(**_JIT)
def unroll_ring(pts: np.ndarray, tpts: np.ndarray, n_cross: int, out: np.ndarray, tout: np.ndarray):
    """Copy the ring buffer into time order; returns the number of points."""
    cap = pts.shape[0]
    k = min(n_cross, cap)
    start = n_cross - k
    for j in range(k):
        slot = (start + j) % cap
        tout[j] = tpts[slot]
        for i in range(pts.shape[1]):
            out[j, i] = pts[slot, i]
    return k


@njit(**_JIT)
def _run_value(
    method, y0, p, n_osc, dc, t_end, t_transient, rtol, atol, h_fixed, max_steps,
    equilibrium_tol, period_tol, max_period, max_points,
    points, t_points, out_i, final_state,
):  # fmt: skip
    """One sweep value: integrate, unroll the points into time order, find the period.

    ``out_i`` receives (count, period, status, n_steps, n_rejected, n_crossings);
    ``points``/``t_points`` must be NaN-filled on entry and stay NaN unless the
    run has an orbit (status "ok").
    """
    n = y0.size
    ring = np.empty((max_points, n))
    tring = np.empty(max_points)
    samples = np.empty((0, n))
    stat_i = np.zeros(N_STAT_I, dtype=np.int64)
    stat_f = np.zeros(N_STAT_F)
    st = integrate(
        method, y0, p, n_osc, dc, t_end, t_transient, rtol, atol, h_fixed, max_steps,
        equilibrium_tol, ring, tring, samples, 1.0, final_state, stat_i, stat_f,
    )  # fmt: skip
    count = 0
    period = 0
    if st == ST_OK:
        count = unroll_ring(ring, tring, stat_i[I_CROSSINGS], points, t_points)
        period = detect_period(points, count, period_tol, max_period)
    out_i[0] = count
    out_i[1] = period
    out_i[2] = st
    out_i[3] = stat_i[I_STEPS]
    out_i[4] = stat_i[I_REJECTED]
    out_i[5] = stat_i[I_CROSSINGS]


#: Columns of the integer output of the sweep kernels.
SWEEP_INT_FIELDS = ("count", "period", "status", "n_steps", "n_rejected", "n_crossings")


@njit(parallel=True, cache=True)
def sweep_chunk(
    method: int,
    y0: np.ndarray,
    params: np.ndarray,
    n_osc: int,
    dc: bool,
    t_end: float,
    t_transient: float,
    rtol: float,
    atol: float,
    h_fixed: float,
    max_steps: int,
    equilibrium_tol: float,
    period_tol: float,
    max_period: int,
    max_points: int,
    lanes: int,
):
    """Restart mode: one independent trajectory from ``y0`` per row of ``params``.

    ``params`` is (n_values, N_PARAMS). Each trajectory is sequential and
    independent, so results do not depend on the thread count, on ``lanes`` or
    on how values are grouped into chunks. Returns (points (n, max_points, n_state),
    t_points (n, max_points), ints (n, 6) with columns SWEEP_INT_FIELDS,
    final_state (n, n_state)); points are in time order and NaN-padded.
    """
    nv = params.shape[0]
    n = y0.size
    points = np.full((nv, max_points, n), np.nan)
    t_points = np.full((nv, max_points), np.nan)
    ints = np.zeros((nv, 6), dtype=np.int64)
    final_state = np.full((nv, n), np.nan)
    # prange splits its range into contiguous blocks, one per thread. Neighbouring
    # values cost about the same (a block of cheap equilibria next to a block of
    # long orbits), so each thread takes an interleaved lane of values instead:
    # pass lanes = the thread count. Results do not depend on it.
    lanes = max(1, min(nv, lanes))
    for lane in prange(lanes):
        for v in range(lane, nv, lanes):
            _run_value(
                method, y0, params[v], n_osc, dc, t_end, t_transient, rtol, atol, h_fixed,
                max_steps, equilibrium_tol, period_tol, max_period, max_points,
                points[v], t_points[v], ints[v], final_state[v],
            )  # fmt: skip
    return points, t_points, ints, final_state


@njit(parallel=True, cache=True)
def continuation_chunk(
    method: int,
    y0: np.ndarray,
    y_starts: np.ndarray,
    params: np.ndarray,
    n_osc: int,
    dc: bool,
    t_end: float,
    t_transient: float,
    rtol: float,
    atol: float,
    h_fixed: float,
    max_steps: int,
    equilibrium_tol: float,
    period_tol: float,
    max_period: int,
    max_points: int,
):
    """Continuation mode: chains of values, each starting from the previous final state.

    ``params`` is (n_chains, length, N_PARAMS) and ``y_starts`` (n_chains,
    n_state) the state each chain starts from. Chains run in parallel; within
    a chain the values run in order. A value whose final state is not finite
    hands ``y0`` to the next one instead. Outputs as :func:`sweep_chunk`, with a
    leading chain axis.
    """
    nc = params.shape[0]
    nl = params.shape[1]
    n = y0.size
    points = np.full((nc, nl, max_points, n), np.nan)
    t_points = np.full((nc, nl, max_points), np.nan)
    ints = np.zeros((nc, nl, 6), dtype=np.int64)
    final_state = np.full((nc, nl, n), np.nan)
    for c in prange(nc):
        y_start = y_starts[c].copy()
        for k in range(nl):
            _run_value(
                method, y_start, params[c, k], n_osc, dc, t_end, t_transient, rtol, atol,
                h_fixed, max_steps, equilibrium_tol, period_tol, max_period, max_points,
                points[c, k], t_points[c, k], ints[c, k], final_state[c, k],
            )  # fmt: skip
            finite = True
            for i in range(n):
                if not math.isfinite(final_state[c, k, i]):
                    finite = False
            for i in range(n):
                y_start[i] = final_state[c, k, i] if finite else y0[i]
    return points, t_points, ints, final_state
