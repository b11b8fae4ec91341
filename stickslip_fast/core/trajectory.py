"""Trajectory and sweep kernels on the driver: parameters in, arrays out.

:func:`integrate` runs one trajectory of the model with any of the three
methods through :func:`driver.drive`, with a :class:`driver.PoincareObserver`
(points at the local minima of x1 in a ring buffer, optional uniform samples)
and classifies the run. :func:`~.sweep_kernels.sweep_chunk` and
:func:`~.sweep_kernels.continuation_chunk` (in :mod:`.sweep_kernels`) run many
trajectories in lanes run on threads (one compiled entry, ``run_lane``). All of them call the same
:func:`_run`, so a sweep value equals the corresponding simulate() bit for bit.

Kernel rules: nothing here raises (``error_model="numpy"``, no bounds that can
fail), every loop is bounded (see :mod:`stickslip_fast.core.driver`), buffers are
allocated once per thread lane outside the step loop, and every output slot of
a value starts as ``ST_NOT_COMPUTED`` so that a value that was never computed
can never pass for a result.

Every entry point takes ``variant`` (:func:`method_variant`): ``None`` for the
explicit methods, :func:`kernel_variant` plus :data:`AUTO_TOKEN` for
``method="auto"`` (:mod:`.autoswitch`, a family of its own), else
:func:`kernel_variant` (for one disk the Rosenbrock runs
integrate :class:`~stickslip_fast.core.problems.StickSlipSmall`, the model with its
sizes known at compile time). Its type picks the method family at compile time,
so Numba compiles only the family and the variant a process uses: a first
``simulate`` with Rodas5P no longer compiles the Dormand-Prince driver as well
(see docs/performance.md, "The first run").
"""

from __future__ import annotations

import math
from collections import namedtuple
from typing import Any

import numpy as np
from numba import types
from numba.extending import overload

from ..base.jit import ENTRY, JIT, OVERLOAD, is_record, njit
from ..base.status import ST_ERROR, ST_OK
from ..model.params import N_PARAMS, P_VB0
from .autoswitch import AUTO_METHOD, N_AUTO_FLAGS, N_AUTO_STATS, AutoMethod
from .driver import (
    S_T_CONVERGED,
    Controls,
    PoincareObserver,
    Section,
    converged_stop,
    disk1_rest_time,
    drive,
    fixed_stop,
    rest_time,
    time_since_crossing,
)
from .poincare import classify, motion_measure
from .problems import (
    SMALL_N_MAX,
    alloc_bordered_linear,
    make_small,
    make_stickslip,
    shape_dims,
    small_shape,
)
from .steppers import (
    DOPRI5_METHOD,
    RODAS4P2_METHOD,
    RODAS4P_METHOD,
    RODAS5P_METHOD,
    RosenbrockMethod,
    alloc_workspace,
)

METHODS = ("rodas5p", "dopri5", "dopri5-fixed", "rodas4p", "rodas4p2", "auto")


M_RODAS5P, M_DOPRI5, M_DOPRI5_FIXED, M_RODAS4P, M_RODAS4P2, M_AUTO = range(6)


#: Appended to :func:`kernel_variant` for ``method="auto"``: a boolean last entry
#: makes the switching method (:mod:`.autoswitch`) a family of its own.
AUTO_TOKEN = (True,)


_JIT = JIT


# slots of the integer and float statistics arrays; I_TO_STIFF ... for method="auto"
# (:data:`.autoswitch.AUTO_STATS`: switches each way, accepted and attempted steps of
# each method)
I_STEPS, I_REJECTED, I_CROSSINGS, I_SAMPLES = range(4)
I_TO_STIFF = 4
N_STAT_I = I_TO_STIFF + N_AUTO_STATS
F_T_FINAL, F_AMPLITUDE, F_T_CONVERGED, F_REST_TIME = range(4)
N_STAT_F = 4


#: The model's Poincare section: dx1 = 0 crossed upwards (local minima of x1).
X1_MINIMA = Section(1, True)


#: The default ``abort`` flag of the kernels: never set.
NO_ABORT = np.zeros(1, dtype=np.int64)


#: Columns of the integer output of the sweep kernels.
SWEEP_INT_FIELDS = ("count", "period", "status", "n_steps", "n_rejected", "n_crossings")


@njit(**_JIT)
def _all_finite(a) -> bool:
    for v in a.flat:
        if not math.isfinite(v):
            return False
    return True


STOP_FIXED, STOP_WHEN_CONVERGED = 0, 1

#: The settings of a trajectory, as the kernels pass them on: (name, type,
#: default) of each field, None where the caller must give it. ``h_fixed`` > 0
#: takes fixed steps; ``stop_kind`` is STOP_FIXED (run to t_end) or
#: STOP_WHEN_CONVERGED (see :func:`stoprules.converged_stop`; ``dwell`` is then
#: the time at rest that counts as an equilibrium).
_RUN_FIELDS = (
    ("t_end", float, None), ("t_transient", float, None), ("rtol", float, None),
    ("atol", float, None), ("h_fixed", float, 0.0), ("max_steps", int, 20_000_000),
    ("equilibrium_tol", float, 1e-4), ("period_tol", float, 1e-5), ("max_period", int, 64),
    ("stop_kind", int, STOP_FIXED), ("dwell", float, 200.0),
)  # fmt: skip
RunSettings = namedtuple(
    "RunSettings", [name for name, _, _ in _RUN_FIELDS],
    defaults=[default for _, _, default in _RUN_FIELDS if default is not None],
)  # fmt: skip


def run_settings(*args: Any, **kwargs: Any) -> RunSettings:
    """A :class:`RunSettings` with the types the kernels are compiled for.

    Takes :class:`RunSettings`' fields (positional or by name; the first four
    are required). Validation is :class:`stickslip_fast.core.settings.Settings`' job.
    """
    given = RunSettings(*args, **kwargs)
    return RunSettings(*(kind(v) for (_, kind, _), v in zip(_RUN_FIELDS, given)))


#: Converged stopping: points repeat over >= 3 periods and >= 8 points.
CONVERGED_MIN_REPEATS = 3


CONVERGED_MIN_POINTS = 8


@njit(**_JIT)
def _stop_rule(rs, n_osc, dc, n):
    if rs.stop_kind == STOP_WHEN_CONVERGED:
        return converged_stop(
            rs.period_tol, rs.max_period, CONVERGED_MIN_REPEATS, CONVERGED_MIN_POINTS,
            rs.equilibrium_tol, rs.dwell, n_osc, dc, n,
        )  # fmt: skip
    return fixed_stop(rs.equilibrium_tol, rs.dwell, n_osc, dc, n)


def kernel_variant(n_osc: int, dc: bool) -> tuple:
    """The compile-time token of the trajectory kernels for N disks and a belt kind.

    :func:`~stickslip_fast.core.problems.small_shape` where a
    :class:`~stickslip_fast.core.problems.StickSlipSmall` kernel exists (N <=
    :data:`~stickslip_fast.core.problems.SMALL_N_MAX`), else ``()`` (the generic
    bordered kernel). Only its type matters. The kernels take it as an argument,
    so Numba compiles only the variants a process uses.
    """
    if 1 <= n_osc <= SMALL_N_MAX:
        return small_shape(n_osc, dc)
    return ()


def method_variant(method: int, n_osc: int, dc: bool) -> tuple | None:
    """The ``variant`` argument of the kernels for a method index (:data:`METHODS`).

    ``None`` for the explicit methods (dopri5, dopri5-fixed: their steps take the
    generic record), else :func:`kernel_variant`. Its type is the compile-time
    choice of the method family: a kernel compiled for one family holds no code
    of the other (the compiled drivers differ in every stage, so each family is a
    separate compile of about half the cold start).
    """
    if method in (M_DOPRI5, M_DOPRI5_FIXED):
        return None
    if method == M_AUTO:
        return kernel_variant(n_osc, dc) + AUTO_TOKEN
    return kernel_variant(n_osc, dc)


def _is_auto(variant) -> bool:
    """At compile time: is ``variant``'s type the token of method="auto" (a boolean last)?"""
    tys = getattr(variant, "types", ())
    return len(tys) > 0 and isinstance(tys[-1], types.Boolean)


def method_record(method, variant):  # noqa: ARG001 - resolved by overload
    """In compiled code: the method record of ``method`` within ``variant``'s family."""


@overload(method_record, **OVERLOAD)
def _method_record(method, variant):
    if isinstance(variant, types.NoneType):
        return lambda method, variant: DOPRI5_METHOD
    if _is_auto(variant):
        return lambda method, variant: AUTO_METHOD
    return lambda method, variant: _rosenbrock(method)


def method_matches(method, variant):  # noqa: ARG001 - resolved by overload
    """In compiled code: True if the method index belongs to ``variant``'s family."""


@overload(method_matches, **OVERLOAD)
def _method_matches(method, variant):
    if isinstance(variant, types.NoneType):
        return lambda method, variant: method == M_DOPRI5 or method == M_DOPRI5_FIXED
    if _is_auto(variant):
        return lambda method, variant: method == M_AUTO
    return lambda method, variant: (
        method == M_RODAS5P or method == M_RODAS4P or method == M_RODAS4P2
    )


def model_problem(method, prob, variant):  # noqa: ARG001 - resolved by overload
    """In compiled code: the record :func:`driver.drive` integrates for the model record ``prob``.

    With a Rosenbrock method and a non-empty ``variant`` (see
    :func:`kernel_variant`) the :class:`StickSlipSmall` twin of ``prob`` (a
    :class:`StickSlip`): the same arithmetic with the sizes known at compile time
    (bit-identical results, 1.6-2.5x faster per step; see docs/developing.md).
    Otherwise ``prob`` itself: explicit methods take the generic record (their steps
    have no linear algebra to gain on). Only the record is chosen here, and
    :func:`_run` calls ``drive`` itself: an overload that called ``drive`` was
    compiled whole once more, just to be typed (Numba compiles an inlined overload's
    implementation before inlining it), about 5 % of a cold start.
    """


@overload(model_problem, **OVERLOAD)
def _model_problem(method, prob, variant):
    small = not isinstance(variant, types.NoneType) and len(variant) > 0
    if is_record(method, AutoMethod):
        # both methods of "auto" take the small record (its f is the generic one's arithmetic)
        if len(variant) > 1:
            return lambda method, prob, variant: make_small(prob, variant[:-1])
        return lambda method, prob, variant: prob
    if is_record(method, RosenbrockMethod) and small:
        return lambda method, prob, variant: make_small(prob, variant)
    return lambda method, prob, variant: prob


def variant_matches(variant, n_osc, dc):  # noqa: ARG001 - resolved by overload
    """True if ``variant`` is None, () or the token of (n_osc, dc)."""


@overload(variant_matches, **OVERLOAD)
def _variant_matches_impl(variant, n_osc, dc):
    if isinstance(variant, types.NoneType) or len(variant) == 0:
        return lambda variant, n_osc, dc: True
    if _is_auto(variant):
        if len(variant) == 1:
            return lambda variant, n_osc, dc: True
        v_osc, v_dc = shape_dims(types.Tuple(variant.types[:-1]))
        return lambda variant, n_osc, dc: n_osc == v_osc and dc == v_dc
    v_osc, v_dc = shape_dims(variant)
    return lambda variant, n_osc, dc: n_osc == v_osc and dc == v_dc


# A compiled function, not inlined: it writes into the observer record that its
# callers get from a call, and stores into such a record from IR-inlined code
# are removed as dead (docs/developing.md, "Borrowed records").
@njit(**_JIT)
def _run(
    method, y0, p, n_osc, dc, variant, rs, p_buf, lin, ws, obs, stop, y, istat, fstat, abort
) -> int:
    """One classified trajectory from y0 with a method record; buffers given.

    With converged stopping the observer watches from t = 0 (``rs.t_transient``
    is not used) and ``fstat[1]`` receives the time of convergence (NaN if the
    run reached t_end first).
    """
    n = y0.size
    prob = make_stickslip(p, n_osc, dc, p_buf)
    for i in range(n):
        y[i] = y0[i]
    fstat[1] = math.nan
    if not (_all_finite(prob.p) and _all_finite(y) and variant_matches(variant, n_osc, dc)):
        obs.counts[0] = 0
        obs.counts[1] = 0
        istat[0] = 0
        istat[1] = 0
        fstat[0] = 0.0
        for i in range(n):
            obs.ymin[i] = math.nan
            obs.ymax[i] = math.nan
        return ST_ERROR
    ctl = Controls(rs.rtol, rs.atol, rs.h_fixed, rs.max_steps)
    status = drive(
        method, model_problem(method, prob, variant), lin, ws, y, rs.t_end, ctl, obs, stop,
        abort, istat, fstat,
    )  # fmt: skip
    fstat[1] = stop.state[S_T_CONVERGED]
    if ws.flags.size == N_AUTO_FLAGS and istat.size >= 2 + N_AUTO_STATS:
        # method="auto" only (the others' flags hold one slot): switches, steps of each method
        for k in range(N_AUTO_STATS):
            istat[2 + k] = ws.flags[N_AUTO_FLAGS - N_AUTO_STATS + k]
    if status == ST_OK:
        t_final = fstat[0]
        vb_end = y[n - 1] if dc else 0.0
        status = classify(
            rest_time(stop, t_final), disk1_rest_time(stop, t_final),
            settled_tail(rs, t_final), time_since_crossing(stop, t_final), dc, vb_end,
            prob.p[P_VB0],
        )  # fmt: skip
    return status


@njit(**_JIT)
def settled_tail(rs, t_final: float) -> float:
    """The time at rest that makes a run an equilibrium: ``dwell``, or the whole
    recording window if that is shorter (see :func:`poincare.classify`)."""
    t_rec = 0.0 if rs.stop_kind == STOP_WHEN_CONVERGED else rs.t_transient
    return min(rs.dwell, t_final - t_rec)


@njit(**_JIT)
def _make_observer(rs, pts, tpts, samples, sample_dt, n):
    t_rec = 0.0 if rs.stop_kind == STOP_WHEN_CONVERGED else rs.t_transient
    return PoincareObserver(
        X1_MINIMA, t_rec, pts, tpts, samples, sample_dt, np.empty(n), np.empty(n),
        np.zeros(2, dtype=np.int64),
    )  # fmt: skip


# inlined (Numba IR): a call boundary here compiled the whole driver once more
@njit(inline="always", **_JIT)
def _run_alone(method, y0, p, n_osc, dc, variant, rs, obs, stop, y, istat, fstat, abort) -> int:
    """:func:`_run` with buffers of its own."""
    n = y0.size
    p_buf = np.empty(N_PARAMS)
    lin = alloc_bordered_linear(n_osc, n)
    ws = alloc_workspace(method, n)
    return _run(
        method, y0, p, n_osc, dc, variant, rs, p_buf, lin, ws, obs, stop, y, istat, fstat, abort
    )


@njit(inline="always", **_JIT)
def _rosenbrock(method: int) -> RosenbrockMethod:
    """The Rosenbrock record of a method index: one type, so one compiled kernel for all."""
    if method == M_RODAS4P:
        return RODAS4P_METHOD
    if method == M_RODAS4P2:
        return RODAS4P2_METHOD
    return RODAS5P_METHOD


@njit(**ENTRY)
def integrate(
    method: int,
    y0: np.ndarray,
    p: np.ndarray,
    n_osc: int,
    dc: bool,
    variant: tuple,
    rs: RunSettings,
    pts: np.ndarray,
    tpts: np.ndarray,
    samples: np.ndarray,
    sample_dt: float,
    y_end: np.ndarray,
    stat_i: np.ndarray,
    stat_f: np.ndarray,
    abort: np.ndarray = NO_ABORT,
) -> int:
    """Integrate one trajectory from t = 0 to ``rs.t_end``; return its status code.

    ``p`` is the packed parameter array (eta' is recomputed from eta here);
    ``rs`` the settings (:func:`run_settings`); ``variant`` is
    :func:`method_variant` of ``method`` (a method of the other family gives
    ST_ERROR). Outputs: ``pts``/``tpts`` (ring
    buffer of the last Poincare points; see ``stat_i[I_CROSSINGS]`` for the
    total), ``samples`` (uniform grid from t_transient), ``y_end`` (state at the
    last accepted time), ``stat_i`` (steps, rejected, crossings, samples; with
    ``N_STAT_I`` slots and method="auto" also switches to stiff and to explicit,
    explicit and Rosenbrock steps accepted and attempted, zero for the other methods) and
    ``stat_f`` (final time, the :func:`motion_measure` of the recording window,
    time of convergence, time at rest at the end: -1 if moving). With ``rs.stop_kind`` STOP_WHEN_CONVERGED the run
    ends once it has converged (see :func:`stoprules.converged_stop`). ``abort``
    (int64[1]) ends the run with "interrupted" when set from another thread.
    """
    n = y0.size
    obs = _make_observer(rs, pts, tpts, samples, sample_dt, n)
    stop = _stop_rule(rs, n_osc, dc, n)
    istat = np.zeros(2 + N_AUTO_STATS, dtype=np.int64)
    fstat = np.zeros(2)
    # the family is the variant's type: one driver compiled, not both. A method of
    # the other family runs on NaN parameters: _run's check returns ST_ERROR.
    p_run = p if method_matches(method, variant) else np.full(p.size, np.nan)
    status = _run_alone(
        method_record(method, variant), y0, p_run, n_osc, dc, variant, rs, obs, stop, y_end,
        istat, fstat, abort,
    )  # fmt: skip
    stat_i[I_STEPS] = istat[0]
    stat_i[I_REJECTED] = istat[1]
    stat_i[I_CROSSINGS] = obs.counts[0]
    stat_i[I_SAMPLES] = obs.counts[1]
    if stat_i.size >= N_STAT_I:
        for k in range(N_AUTO_STATS):
            stat_i[I_TO_STIFF + k] = istat[2 + k]
    stat_f[F_T_FINAL] = fstat[0]
    stat_f[F_AMPLITUDE] = motion_measure(obs.ymin, obs.ymax, n_osc, dc)
    stat_f[F_T_CONVERGED] = fstat[1]
    stat_f[F_REST_TIME] = rest_time(stop, fstat[0])
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
