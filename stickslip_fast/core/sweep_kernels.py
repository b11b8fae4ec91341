"""The sweep kernels: many values of a parameter in parallel lanes on the one driver.

:func:`sweep_chunk` restarts every value from y0 (or from its own start), and
:func:`continuation_chunk` chains each value from the previous value's final state. Both write
the per-value outputs the result files store (status ``ST_NOT_COMPUTED`` until computed)."""

from __future__ import annotations

import numpy as np
from numba import njit, prange

from ..base.status import ST_NOT_COMPUTED, ST_OK, ST_UNSETTLED
from ..model.params import N_PARAMS
from .poincare import detect_period
from .problems import (
    alloc_bordered_linear,
)
from .steppers import alloc_workspace
from .trajectory import (
    _JIT,
    _PJIT,
    NO_ABORT,
    RunSettings,
    _all_finite,
    _make_observer,
    _run,
    _stop_rule,
    method_matches,
    method_record,
    unroll_ring,
)


@njit(**_JIT)
def _lane_values(
    method, first, stride, count, y0s, chain, params, n_osc, dc, variant, rs, max_points, points,
    t_points, ints, t_conv, final_state, abort,
):  # fmt: skip
    """Run values ``first + k * stride`` (k < count) with one set of buffers.

    ``params``, ``points``, ``t_points``, ``ints``, ``t_conv`` and
    ``final_state`` are indexed by value. Restart (``chain`` False): every value
    starts from ``y0s[v]``. Chain (``chain`` True): value k starts from the
    final state of the last value before it that did not fail (``y0s[first]``
    for the first, and when none did).
    """
    n = y0s.shape[1]
    p_buf = np.empty(N_PARAMS)
    lin = alloc_bordered_linear(n_osc, n)
    ws = alloc_workspace(method, n)
    obs = _make_observer(
        rs, np.empty((max_points, n)), np.empty(max_points), np.empty((0, n)), 1.0, n
    )
    stop = _stop_rule(rs, n_osc, dc, n)
    y = np.empty(n)
    start = y0s[first].copy()
    istat = np.zeros(2, dtype=np.int64)
    fstat = np.zeros(2)
    for k in range(count):
        v = first + k * stride
        y_from = start if chain else y0s[v]
        st = _run(
            method, y_from, params[v], n_osc, dc, variant, rs, p_buf, lin, ws, obs, stop, y,
            istat, fstat, abort,
        )  # fmt: skip
        count_pts = 0
        period = 0
        if st == ST_OK:
            count_pts = unroll_ring(obs.pts, obs.tpts, obs.counts[0], points[v], t_points[v])
            period = detect_period(points[v], count_pts, rs.period_tol, rs.max_period)
        for i in range(n):
            final_state[v, i] = y[i]
        t_conv[v] = fstat[1]
        out = ints[v]
        out[0] = count_pts
        out[1] = period
        out[3] = istat[0]
        out[4] = istat[1]
        out[5] = obs.counts[0]
        out[2] = st
        if chain and _usable_start(st) and _all_finite(y):
            for i in range(n):
                start[i] = y[i]


@njit(**_JIT)
def _usable_start(status: int) -> bool:
    # a failed run's final state is no start for the next value of a chain
    # ok, equilibrium, stalled, no-crossings, unsettled
    return 0 <= status <= 3 or status == ST_UNSETTLED


# inlined (Numba IR): a call boundary here compiled the whole driver once more
@njit(inline="always", **_JIT)
def _lane_dispatch(
    method, first, stride, count, y0s, chain, params, n_osc, dc, variant, rs, max_points, points,
    t_points, ints, t_conv, final_state, abort,
):  # fmt: skip
    # as in integrate(): the variant's type is the method family; a method of the
    # other family runs on NaN parameters, so every value gets ST_ERROR
    p_run = params if method_matches(method, variant) else np.full_like(params, np.nan)
    _lane_values(
        method_record(method, variant), first, stride, count, y0s, chain, p_run, n_osc, dc,
        variant, rs, max_points, points, t_points, ints, t_conv, final_state, abort,
    )  # fmt: skip


@njit(**_JIT)
def _outputs(nv: int, max_points: int, n: int):
    points = np.full((nv, max_points, n), np.nan)
    t_points = np.full((nv, max_points), np.nan)
    ints = np.zeros((nv, 6), dtype=np.int64)
    ints[:, 2] = ST_NOT_COMPUTED
    final_state = np.full((nv, n), np.nan)
    t_conv = np.full(nv, np.nan)
    return points, t_points, ints, t_conv, final_state


@njit(**_PJIT)
def _parallel_lanes(
    method, n_lanes, chain, lane_len, y0s, params, n_osc, dc, variant, rs, max_points, points,
    t_points, ints, t_conv, final_state, abort,
):  # fmt: skip
    """The one ``prange`` loop of both chunk kernels (one parallel compile per variant).

    Restart (``chain`` 0): lane k runs values k, k + n_lanes, ... Chains
    (``chain`` 1): lane k runs values k * lane_len ... (k + 1) * lane_len - 1
    in order, each from the previous final state.
    """
    nv = params.shape[0]
    for lane in prange(n_lanes):
        k = np.int64(lane)  # the prange index may be unsigned: keep index arithmetic int64
        first = k
        stride = np.int64(n_lanes)
        count = (nv - k + stride - 1) // stride
        if chain:
            first = k * lane_len
            stride = np.int64(1)
            count = np.int64(lane_len)
        _lane_dispatch(
            method, first, stride, count, y0s, chain, params, n_osc, dc, variant, rs, max_points,
            points, t_points, ints, t_conv, final_state, abort,
        )  # fmt: skip


@njit(**_JIT)
def sweep_chunk(
    method: int,
    y0: np.ndarray,
    params: np.ndarray,
    n_osc: int,
    dc: bool,
    variant: tuple | None,
    rs: RunSettings,
    max_points: int,
    lanes: int,
    abort: np.ndarray = NO_ABORT,
):
    """Restart mode: one independent trajectory from ``y0`` per row of ``params``.

    ``params`` is (n_values, N_PARAMS); ``y0`` is one start (n_state,) for all
    values or one per value (n_values, n_state). Each trajectory is sequential
    and independent, so results do not depend on the thread count, on ``lanes``
    or on how values are grouped into chunks. Returns (points (n, max_points,
    n_state), t_points (n, max_points), ints (n, 6) with columns
    SWEEP_INT_FIELDS, t_converged (n,), final_state (n, n_state)); points are
    in time order and NaN-padded. ``rs``: see :func:`run_settings`.
    A value whose status is still ST_NOT_COMPUTED (-1) was not run (``abort``
    was set); callers must not store it.
    """
    nv = params.shape[0]
    y0s = _starts(y0, nv)
    n = y0s.shape[1]
    points, t_points, ints, t_conv, final_state = _outputs(nv, max_points, n)
    # prange splits its range into contiguous blocks, one per thread. Neighbouring
    # values cost about the same (a block of cheap equilibria next to a block of
    # long orbits), so each thread takes an interleaved lane of values instead:
    # pass lanes = the thread count. Results do not depend on it.
    lanes = max(1, min(nv, lanes))
    # np.int64(...), not literals: literal arguments would compile a second copy
    _parallel_lanes(
        method, lanes, np.int64(0), np.int64(0), y0s, np.ascontiguousarray(params), n_osc, dc, variant, rs, max_points, points,
        t_points, ints, t_conv, final_state, abort,
    )  # fmt: skip
    return points, t_points, ints, t_conv, final_state


@njit(**_JIT)
def _starts(y0, nv):
    """One start per value: broadcast a single (n_state,) start."""
    if y0.ndim == 2:
        return np.ascontiguousarray(y0.reshape(-1, y0.shape[-1]))
    out = np.empty((nv, y0.shape[-1]))
    for v in range(nv):
        for i in range(y0.shape[-1]):
            out[v, i] = y0.flat[i]
    return out


@njit(**_JIT)
def continuation_chunk(
    method: int,
    y0: np.ndarray,
    y_starts: np.ndarray,
    params: np.ndarray,
    n_osc: int,
    dc: bool,
    variant: tuple,
    rs: RunSettings,
    max_points: int,
    abort: np.ndarray = NO_ABORT,
):
    """Continuation mode: chains of values, each starting from the previous final state.

    ``params`` is (n_chains, length, N_PARAMS) and ``y_starts`` (n_chains,
    n_state) the state each chain starts from. Chains run in parallel; within
    a chain the values run in order. After a value that failed (nonfinite,
    step-underflow, max-steps, error, interrupted) the next value starts from
    the last good final state of the chain (``y_starts[c]`` if there is none);
    ``y0`` is unused and kept for the call signature. Outputs as
    :func:`sweep_chunk`, with a leading chain axis.
    """
    nc = params.shape[0]
    nl = params.shape[1]
    n = y_starts.shape[1]
    flat = params.reshape(nc * nl, params.shape[2])
    points, t_points, ints, t_conv, final_state = _outputs(nc * nl, max_points, n)
    starts = np.empty((nc * nl, n))
    for c in range(nc):
        for i in range(n):
            starts[c * nl, i] = y_starts[c, i]
    _parallel_lanes(
        method, nc, np.int64(1), np.int64(nl), starts, np.ascontiguousarray(flat), n_osc, dc, variant, rs,
        max_points, points, t_points, ints, t_conv, final_state, abort,
    )  # fmt: skip
    return (
        points.reshape(nc, nl, max_points, n),
        t_points.reshape(nc, nl, max_points),
        ints.reshape(nc, nl, 6),
        t_conv.reshape(nc, nl),
        final_state.reshape(nc, nl, n),
    )
