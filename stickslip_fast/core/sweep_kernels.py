"""The sweep kernels: many values of a parameter in parallel lanes on the one driver.

:func:`sweep_chunk` restarts every value from y0 (or from its own start), and
:func:`continuation_chunk` chains each value from the previous value's final state. Both write
the per-value outputs the result files store (status ``ST_NOT_COMPUTED`` until computed)."""

from __future__ import annotations

from concurrent.futures import ThreadPoolExecutor

import numba
import numpy as np

from ..base.jit import ENTRY, njit
from ..base.status import ST_NOT_COMPUTED, ST_OK, ST_UNSETTLED
from ..model.params import N_PARAMS
from .poincare import orbit_period
from .problems import (
    alloc_bordered_linear,
)
from .steppers import alloc_workspace
from .trajectory import (
    _JIT,
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
            period = orbit_period(
                points[v], count_pts, rs.period_tol, rs.max_period, params[v], n_osc, dc
            )
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


@njit(**ENTRY)
def run_lane(
    method, lane, n_lanes, chain, lane_len, y0s, params, n_osc, dc, variant, rs, max_points,
    points, t_points, ints, t_conv, final_state, abort,
):  # fmt: skip
    """One lane of a chunk (the compiled entry point that :func:`_run_lanes` schedules).

    Restart (``chain`` 0): lane k runs values k, k + n_lanes, ... Chains
    (``chain`` 1): lane k runs values k * lane_len ... (k + 1) * lane_len - 1
    in order, each from the previous final state. Each lane writes only its own
    values' rows of the outputs.
    """
    nv = params.shape[0]
    first = lane
    stride = n_lanes
    count = (nv - lane + stride - 1) // stride
    if chain:
        first = lane * lane_len
        stride = np.int64(1)
        count = lane_len
    _lane_dispatch(
        method, first, stride, count, y0s, chain, params, n_osc, dc, variant, rs, max_points,
        points, t_points, ints, t_conv, final_state, abort,
    )  # fmt: skip


def _outputs(nv: int, max_points: int, n: int) -> tuple:
    points = np.full((nv, max_points, n), np.nan)
    t_points = np.full((nv, max_points), np.nan)
    ints = np.zeros((nv, 6), dtype=np.int64)
    ints[:, 2] = ST_NOT_COMPUTED
    final_state = np.full((nv, n), np.nan)
    t_conv = np.full(nv, np.nan)
    return points, t_points, ints, t_conv, final_state


def _run_lanes(n_lanes: int, threads: int, args: tuple, outputs: tuple, abort) -> None:
    """Run lanes 0 .. n_lanes - 1 of :func:`run_lane` on ``threads`` threads.

    The lanes are scheduled here, in Python threads, not by a ``prange`` loop:
    :func:`run_lane` is compiled with ``nogil=True``, so the threads run in
    parallel, and a parallel loop around the driver compiled it twice more
    (the loop body and the function around it: ~15 s of a first sweep's ~56 s;
    docs/performance.md, "The first run"). Each value is computed by the same
    sequential code whichever thread runs it, so results do not depend on
    ``threads``.
    """
    method, chain, lane_len, y0s, params, n_osc, dc, variant, rs, max_points = args

    def lane(k: int) -> None:
        run_lane(
            method, np.int64(k), np.int64(n_lanes), chain, lane_len, y0s, params, n_osc, dc,
            variant, rs, max_points, *outputs, abort,
        )  # fmt: skip

    threads = max(1, min(int(threads), n_lanes))
    if threads == 1:
        for k in range(n_lanes):
            lane(k)
        return
    with ThreadPoolExecutor(max_workers=threads, thread_name_prefix="stickslip-lane") as pool:
        for future in [pool.submit(lane, k) for k in range(n_lanes)]:
            future.result()


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
) -> tuple:
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
    y0s = _starts(np.asarray(y0, dtype=float), nv)
    outputs = _outputs(nv, max_points, y0s.shape[1])
    # Neighbouring values cost about the same (a block of cheap equilibria next
    # to a block of long orbits), so each thread takes an interleaved lane of
    # values: lanes = the thread count. Results do not depend on it.
    lanes = max(1, min(nv, int(lanes)))
    # np.int64(...), not Python ints: the compiled entry is typed once
    args = (np.int64(method), np.int64(0), np.int64(0), y0s, _owned(params),
            n_osc, dc, variant, rs, max_points)  # fmt: skip
    _run_lanes(lanes, lanes, args, outputs, abort)
    return outputs


def _owned(a: np.ndarray) -> np.ndarray:
    """A writable C-contiguous float copy: the compiled entry is typed once.

    Numba types an array by its layout and its read-only flag, so a read-only view
    (``np.broadcast_to`` of one start, read-only input) compiled :func:`run_lane` a
    second time: ~5 s on a cold cache (a one-value sweep, a chunk of one value, the
    Dask warm-up).
    """
    return np.array(a, dtype=np.float64, order="C", copy=True)


def _starts(y0: np.ndarray, nv: int) -> np.ndarray:
    """One start per value: a single (n_state,) start repeated."""
    if y0.ndim == 2:
        return _owned(y0.reshape(-1, y0.shape[-1]))
    return _owned(np.broadcast_to(y0.reshape(-1), (nv, y0.shape[-1])))


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
) -> tuple:
    """Continuation mode: chains of values, each starting from the previous final state.

    ``params`` is (n_chains, length, N_PARAMS) and ``y_starts`` (n_chains,
    n_state) the state each chain starts from. Chains run in parallel (on
    ``numba.get_num_threads()`` threads); within a chain the values run in
    order. After a value that failed (nonfinite, step-underflow, max-steps,
    error, interrupted) the next value starts from the last good final state of
    the chain (``y_starts[c]`` if there is none); ``y0`` is unused and kept for
    the call signature. Outputs as :func:`sweep_chunk`, with a leading chain axis.
    """
    nc, nl = params.shape[0], params.shape[1]
    n = y_starts.shape[1]
    flat = _owned(params.reshape(nc * nl, params.shape[2]))
    outputs = _outputs(nc * nl, max_points, n)
    starts = np.empty((nc * nl, n))
    starts[::nl] = y_starts  # only each chain's first row is read
    args = (np.int64(method), np.int64(1), np.int64(nl), starts, flat, n_osc, dc, variant, rs,
            max_points)  # fmt: skip
    _run_lanes(nc, numba.get_num_threads(), args, outputs, abort)
    points, t_points, ints, t_conv, final_state = outputs
    return (
        points.reshape(nc, nl, max_points, n),
        t_points.reshape(nc, nl, max_points),
        ints.reshape(nc, nl, 6),
        t_conv.reshape(nc, nl),
        final_state.reshape(nc, nl, n),
    )
