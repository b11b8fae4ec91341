"""Generic compiled steppers, one per method family, over any problem record.

A *method* is a record of tableau arrays (:data:`RODAS5P_METHOD`,
:data:`RODAS4P_METHOD`, :data:`RODAS4P2_METHOD`, :data:`DOPRI5_METHOD`; the
coefficients live in :mod:`stickslip_fast.core.tableaus`). The Rosenbrock records
all have the same Numba type, so one compiled kernel serves every tableau.
A *problem* is a record of :mod:`stickslip_fast.core.problems` (or
:mod:`stickslip_fast.core.testproblems`): the steppers call only ``problem_f``,
``problem_jac``, ``problem_factor`` and ``problem_solve`` on it, which Numba
dispatches on the record's type. A :class:`StepWorkspace` holds every array a
step needs; the caller allocates it once (``alloc_workspace``), and
no step allocates.

The generic functions (overloaded per method record):

- ``stepper_init(method, prob, lin, y, ws)``: f(y) into ``ws.f0`` (and the FSAL stage);
- ``stepper_step(method, prob, lin, y, h, ws) -> bool``: one step from y into
  ``ws.ynew`` with the error estimate in ``ws.err``; False if W is singular or
  a stage is not finite;
- ``stepper_accept(method, prob, y, ws, modified)``: bookkeeping after an
  accepted step (``modified``: an observer changed the new state);
- ``stepper_dense(method, ws, h)``: dense-output coefficients ``ws.D`` of the
  last step, built only for the steps that need them.

Dense-output kinds
------------------
``DENSE_POLY`` (explicit RK): y(theta) = y0 + sum_r theta^(r+1) D[r].
``DENSE_HERMITE`` (Rosenbrock): y(theta) = (1-theta) y0 + theta (y1 + (1-theta)
(D[0] + theta (D[1] + theta D[2] ...))).
"""

from __future__ import annotations

import math
from collections import namedtuple

import numpy as np
from numba.extending import overload

from ..base.jit import JIT, OVERLOAD, is_record, njit, overload_call
from .problems import (
    error_norm,
    initial_step,
    problem_f,
    problem_factor,
    problem_jac,
    problem_solve,
)
from .tableaus import DOPRI5, RODAS4P, RODAS4P2, RODAS5P

__all__ = [
    "DENSE_POLY",
    "DENSE_HERMITE",
    "RosenbrockMethod",
    "ExplicitRKMethod",
    "RODAS5P_METHOD",
    "RODAS4P_METHOD",
    "RODAS4P2_METHOD",
    "rosenbrock_method",
    "DOPRI5_METHOD",
    "StepWorkspace",
    "alloc_workspace",
    "stepper_init",
    "stepper_step",
    "stepper_accept",
    "stepper_dense",
    "dense_value",
    "dense_state",
    "error_norm",
    "initial_step",
    "rejected_step_factor",
    "accepted_step_factor",
]

DENSE_POLY = 0
DENSE_HERMITE = 1

_JIT = JIT
_OVL = OVERLOAD

#: A Rosenbrock-Wanner method in transformed form; ``q`` is the order of the
#: error estimate plus one (the exponent of the step-size controller).
RosenbrockMethod = namedtuple("RosenbrockMethod", ["gamma", "a", "C", "b", "b_err", "H", "q"])
#: An explicit Runge-Kutta method with FSAL and a polynomial continuous extension:
#: ``P`` (dense rows, stages) is the transpose of the tableau's ``dense``.
ExplicitRKMethod = namedtuple("ExplicitRKMethod", ["A", "b", "b_err", "P", "q"])


def rosenbrock_method(tableau) -> RosenbrockMethod:
    """The method record of a :class:`~stickslip_fast.core.tableau_types.RosenbrockTableau`."""
    return RosenbrockMethod(
        float(tableau.gamma), tableau.a, tableau.C, np.ascontiguousarray(tableau.b),
        np.ascontiguousarray(tableau.b_err), tableau.H, tableau.embedded_order + 1.0,
    )  # fmt: skip


RODAS5P_METHOD = rosenbrock_method(RODAS5P)
RODAS4P_METHOD = rosenbrock_method(RODAS4P)
RODAS4P2_METHOD = rosenbrock_method(RODAS4P2)
DOPRI5_METHOD = ExplicitRKMethod(
    DOPRI5.A, DOPRI5.b, DOPRI5.b_err, np.ascontiguousarray(DOPRI5.dense.T), 5.0
)

#: Everything one step needs. ``K`` (stages, n), ``D`` (dense rows, n), the
#: rest (n,) but ``flags`` (int64[1]: 1 while the Jacobian is fresh at y).
StepWorkspace = namedtuple(
    "StepWorkspace", ["K", "ytmp", "ftmp", "f0", "ynew", "err", "D", "flags"]
)


_is = is_record


@njit(**_JIT)
def _alloc(stages: int, dense_rows: int, n: int) -> StepWorkspace:
    return StepWorkspace(
        np.zeros((stages, n)), np.zeros(n), np.zeros(n), np.zeros(n), np.zeros(n),
        np.zeros(n), np.zeros((dense_rows, n)), np.zeros(1, dtype=np.int64),
    )  # fmt: skip


def alloc_workspace(method, n):  # noqa: ARG001 - resolved by overload
    """In compiled code: a :class:`StepWorkspace` for ``method`` on n states."""


@overload(alloc_workspace, **_OVL)
def _alloc_workspace(method, n):
    if _is(method, RosenbrockMethod):
        return lambda method, n: _alloc(method.b.size, method.H.shape[0], n)
    if _is(method, ExplicitRKMethod):
        return lambda method, n: _alloc(method.b.size, method.P.shape[0], n)


# ------------------------------------------------------------------ step control
# PI controller (Gustafsson; Hairer-Wanner IV.2): fac = 0.9 err^(-alpha/q)
# err_prev^(beta/q), q the order of the error estimate plus one. Shared by every
# adaptive kernel, the CUDA one included. The gains are Hairer and Wanner's DOPRI5
# choice (alpha/q = 0.17, beta/q = 0.04 at q = 5), chosen by measurement over
# OrdinaryDiffEq.jl's PIController gains (0.7, 0.4): 9-27 % fewer attempts at
# matched Poincare accuracy (benchmarks/controllers.py), ~1.2x fewer steps over
# every data/ diagram with the same status, period and points
# (scripts/compare_controllers.py, docs/model.md "Step-size control").
STEP_SAFETY = 0.9
STEP_FAC_MIN = 0.2
STEP_FAC_MAX = 6.0
PI_ALPHA = 0.85
PI_BETA = 0.2


@njit(**_JIT)
def rejected_step_factor(en: float, finite: bool, q: float) -> float:
    """Step-size factor after a rejected step (error norm ``en`` > 1, or a non-finite stage)."""
    if not finite:
        return 0.25
    return max(STEP_FAC_MIN, STEP_SAFETY * en ** (-1.0 / q))


@njit(**_JIT)
def accepted_step_factor(en: float, err_prev: float, q: float, after_reject: bool) -> float:
    """PI step-size factor after an accepted step; no growth right after a rejection."""
    en = max(en, 1e-10)
    fac = STEP_SAFETY * en ** (-PI_ALPHA / q) * err_prev ** (PI_BETA / q)
    fac = min(STEP_FAC_MAX, max(STEP_FAC_MIN, fac))
    if after_reject:
        fac = min(fac, 1.0)
    return fac


# ------------------------------------------------------------------ generic API
def stepper_init(method, prob, lin, y, ws):  # noqa: ARG001 - resolved by overload
    """f(y) into ws.f0 (and the first FSAL stage); the Jacobian is marked stale."""


def stepper_step(method, prob, lin, y, h, ws):  # noqa: ARG001
    """One step of size h from y; see the module docstring."""


def stepper_accept(method, prob, lin, y, ws, modified):  # noqa: ARG001
    """Bookkeeping after an accepted step (y is the new state)."""


def stepper_dense(method, ws, h):  # noqa: ARG001
    """Dense-output coefficients of the last step into ws.D."""


def stepper_dense_kind(method):  # noqa: ARG001
    """DENSE_POLY or DENSE_HERMITE."""


# --------------------------------------------------------------------------- ERK
@njit(inline="always", **_JIT)
def erk_step(A, b, b_err, prob, y0, h, K, ytmp, y1, err) -> None:
    """One explicit RK step (FSAL): K[0] must hold f(y0) on entry.

    On return y1 is the new state, err the embedded error estimate and K[s-1]
    holds f(y1) (FSAL).
    """
    s = b.size
    n = y0.size
    for st in range(1, s):
        for i in range(n):
            acc = 0.0
            for j in range(st):
                acc += A[st, j] * K[j, i]
            ytmp[i] = y0[i] + h * acc
        if st == s - 1:
            # FSAL: the last stage is evaluated at the new solution itself
            for i in range(n):
                y1[i] = ytmp[i]
        problem_f(prob, ytmp, K[st])
    for i in range(n):
        e = 0.0
        for j in range(s):
            e += b_err[j] * K[j, i]
        err[i] = h * e


@njit(inline="always", **_JIT)
def erk_init(prob, y, ws) -> None:
    """f(y) into ws.f0 and ws.K[0] (FSAL: the first stage of the first step)."""
    problem_f(prob, y, ws.f0)
    for i in range(y.size):
        ws.K[0, i] = ws.f0[i]


@njit(inline="always", **_JIT)
def erk_accept(erk, prob, y, ws, modified) -> None:
    """After an accepted step of the explicit tableau ``erk``: the next first stage f(y)
    into ws.K[0], the FSAL stage unless the step's end was modified (an event)."""
    if modified:
        problem_f(prob, y, ws.K[0])
    else:
        last = erk.b.size - 1
        for i in range(y.size):
            ws.K[0, i] = ws.K[last, i]


@njit(inline="always", **_JIT)
def ros_step(ros, prob, lin, y, h, ws) -> bool:
    """One step of the Rosenbrock tableau ``ros``, the Jacobian evaluated at y first where
    the workspace's is stale (``ws.flags[0] == 0``); False if W is singular."""
    if ws.flags[0] == 0:
        problem_jac(prob, y, lin)
        ws.flags[0] = 1
    return rosenbrock_step(
        ros.gamma, ros.a, ros.C, ros.b, ros.b_err, prob, lin, y, ws.f0, h, ws.K, ws.ytmp,
        ws.ftmp, ws.ynew, ws.err,
    )  # fmt: skip


@overload_call(stepper_init)
def _erk_init(method, prob, lin, y, ws):
    if _is(method, ExplicitRKMethod):
        return lambda method, prob, lin, y, ws: erk_init(prob, y, ws)
    if _is(method, RosenbrockMethod):

        def impl(method, prob, lin, y, ws):
            problem_f(prob, y, ws.f0)
            ws.flags[0] = 0

        return impl


@overload_call(stepper_step)
def _step(method, prob, lin, y, h, ws):
    if _is(method, ExplicitRKMethod):

        def impl(method, prob, lin, y, h, ws):
            erk_step(method.A, method.b, method.b_err, prob, y, h, ws.K, ws.ytmp, ws.ynew, ws.err)
            return True

        return impl
    if _is(method, RosenbrockMethod):
        return lambda method, prob, lin, y, h, ws: ros_step(method, prob, lin, y, h, ws)


@overload_call(stepper_accept)
def _accept(method, prob, lin, y, ws, modified):
    if _is(method, ExplicitRKMethod):
        return lambda method, prob, lin, y, ws, modified: erk_accept(method, prob, y, ws, modified)
    if _is(method, RosenbrockMethod):

        def impl(method, prob, lin, y, ws, modified):
            problem_f(prob, y, ws.f0)
            ws.flags[0] = 0

        return impl


@njit(inline="always", **_JIT)
def _stage_combination(M, K, scale, D) -> None:
    """D = scale * M K: dense-output coefficients from the stages (M is rows x stages)."""
    s = M.shape[1]
    for r in range(M.shape[0]):
        for i in range(K.shape[1]):
            acc = 0.0
            for j in range(s):
                acc += M[r, j] * K[j, i]
            D[r, i] = scale * acc


@overload_call(stepper_dense)
def _dense(method, ws, h):
    if _is(method, ExplicitRKMethod):
        return lambda method, ws, h: _stage_combination(method.P, ws.K, h, ws.D)
    if _is(method, RosenbrockMethod):
        return lambda method, ws, h: _stage_combination(method.H, ws.K, 1.0, ws.D)


@overload(stepper_dense_kind, **_OVL)
def _dense_kind(method):
    if _is(method, ExplicitRKMethod):
        return lambda method: DENSE_POLY
    if _is(method, RosenbrockMethod):
        return lambda method: DENSE_HERMITE


# -------------------------------------------------------------------- Rosenbrock
@njit(inline="always", **_JIT)
def rosenbrock_step(gamma, a, C, b, b_err, prob, lin, y0, f0, h, K, ytmp, ftmp, y1, err) -> bool:
    """One Rosenbrock-Wanner step for an autonomous system (transformed form).

    Solves, with W = I / (h gamma) - J(y0),

        W k_i = f(y0 + sum_{j<i} a_ij k_j) + sum_{j<i} (C_ij / h) k_j

    and sets y1 = y0 + sum_i b_i k_i and err = sum_i b_err_i k_i; the stages
    stay in K for the dense output. ``f0`` is f(y0); the Jacobian in ``lin``
    must have been evaluated at y0. Returns False if W is singular or a stage
    is not finite.
    """
    s = b.size
    n = y0.size
    if not problem_factor(prob, lin, 1.0 / (h * gamma)):
        return False
    inv_h = 1.0 / h
    for st in range(s):
        if st == 0:
            for i in range(n):
                ftmp[i] = f0[i]
        else:
            for i in range(n):
                acc = 0.0
                for j in range(st):
                    acc += a[st, j] * K[j, i]
                ytmp[i] = y0[i] + acc
            problem_f(prob, ytmp, ftmp)
        kst = K[st]
        for i in range(n):
            acc = 0.0
            for j in range(st):
                acc += C[st, j] * K[j, i]
            kst[i] = ftmp[i] + inv_h * acc
        problem_solve(prob, lin, kst)
        for i in range(n):
            if not math.isfinite(kst[i]):
                return False
    for i in range(n):
        acc = 0.0
        e = 0.0
        for j in range(s):
            acc += b[j] * K[j, i]
            e += b_err[j] * K[j, i]
        y1[i] = y0[i] + acc
        err[i] = e
    return True


# ------------------------------------------------------------------ dense output
@njit(**_JIT)
def dense_value(kind: int, theta: float, y0, y1, D, i: int) -> float:
    """Component i of the dense output at theta in [0, 1]."""
    nd = D.shape[0]
    if kind == DENSE_POLY:
        acc = 0.0
        for r in range(nd - 1, -1, -1):
            acc = theta * (D[r, i] + acc)
        return y0[i] + acc
    inner = 0.0
    for r in range(nd - 1, -1, -1):
        inner = D[r, i] + theta * inner
    th1 = 1.0 - theta
    return th1 * y0[i] + theta * (y1[i] + th1 * inner)


@njit(**_JIT)
def dense_state(kind: int, theta: float, y0, y1, D, out) -> None:
    """The whole state of the dense output at theta into ``out``."""
    for i in range(out.size):
        out[i] = dense_value(kind, theta, y0, y1, D, i)
