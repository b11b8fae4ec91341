"""Standard test problems with known solutions, as problem records for the generic steppers.

They check the steppers and the driver apart from the stick-slip model
(tests/test_steppers.py), and they are the worked example of how to add a
problem: a namedtuple record, a linear workspace (:class:`DenseLinear`), and one
``overload`` of each generic function of :mod:`stickslip_fast.core.problems` that has no
default (the error norm and the starting step have).

:class:`LinearProblem`
    y' = A y; exact solution expm(A t) y0.
:class:`Kaps`
    y1' = -(2 + 1/eps) y1 + y2^2 / eps, y2' = y1 - y2 - y2^2; from (1, 1) the
    exact solution is y1 = exp(-2t), y2 = exp(-t) for every eps (stiff for
    small eps).
:class:`ProtheroRobinson`
    y' = lam (y - sin t) + cos t, made autonomous with z = (y, t); from
    (0, 0) the exact solution is y = sin t (stiff for lam << -1). Methods
    that lose order on it show order reduction.
:class:`VanDerPol`
    y1' = y2, y2' = mu (1 - y1^2) y2 - y1: non-stiff for mu ~ 1; for mu >> 1
    stiff along its slow branches and non-stiff in its fast jumps (the test
    of ``method="auto"``, :func:`solve_test_problem_auto`). No closed form.
"""

from __future__ import annotations

import math
from collections import namedtuple

import numpy as np
from numba import types
from numba.extending import overload

from ..base.jit import ENTRY, JIT, OVERLOAD, njit
from ..model.linalg import dense_w_factor, dense_w_solve
from . import problems
from .autoswitch import AUTO_METHOD, N_AUTO_FLAGS, N_AUTO_STATS
from .driver import STOP_AT_END, Controls, PoincareObserver, Section, drive, simple_stop
from .steppers import DOPRI5_METHOD, RODAS5P_METHOD, alloc_workspace

__all__ = [
    "LinearProblem",
    "Kaps",
    "ProtheroRobinson",
    "VanDerPol",
    "DenseLinear",
    "solve_test_problem",
    "solve_test_problem_auto",
]

_JIT = JIT
_OVL = OVERLOAD

LinearProblem = namedtuple("LinearProblem", ["A"])
Kaps = namedtuple("Kaps", ["eps"])
ProtheroRobinson = namedtuple("ProtheroRobinson", ["lam"])
VanDerPol = namedtuple("VanDerPol", ["mu"])
#: Dense Jacobian, its W = sigma I - J factors and pivots.
DenseLinear = namedtuple("DenseLinear", ["jac", "lu", "piv"])


# -------------------------------------------- each problem's f and Jacobian
@njit(inline="always", **_JIT)
def _linear_f(prob, y, out):
    n = y.size
    for i in range(n):
        acc = 0.0
        for j in range(n):
            acc += prob.A[i, j] * y[j]
        out[i] = acc


@njit(inline="always", **_JIT)
def _linear_jac(prob, y, lin):
    lin.jac[:, :] = prob.A


@njit(inline="always", **_JIT)
def _kaps_f(prob, y, out):
    out[0] = -(2.0 + 1.0 / prob.eps) * y[0] + y[1] * y[1] / prob.eps
    out[1] = y[0] - y[1] - y[1] * y[1]


@njit(inline="always", **_JIT)
def _kaps_jac(prob, y, lin):
    lin.jac[0, 0] = -(2.0 + 1.0 / prob.eps)
    lin.jac[0, 1] = 2.0 * y[1] / prob.eps
    lin.jac[1, 0] = 1.0
    lin.jac[1, 1] = -1.0 - 2.0 * y[1]


@njit(inline="always", **_JIT)
def _prothero_robinson_f(prob, y, out):
    out[0] = prob.lam * (y[0] - math.sin(y[1])) + math.cos(y[1])
    out[1] = 1.0


@njit(inline="always", **_JIT)
def _prothero_robinson_jac(prob, y, lin):
    lin.jac[0, 0] = prob.lam
    lin.jac[0, 1] = -prob.lam * math.cos(y[1]) - math.sin(y[1])
    lin.jac[1, 0] = 0.0
    lin.jac[1, 1] = 0.0


@njit(inline="always", **_JIT)
def _van_der_pol_f(prob, y, out):
    out[0] = y[1]
    out[1] = prob.mu * (1.0 - y[0] * y[0]) * y[1] - y[0]


@njit(inline="always", **_JIT)
def _van_der_pol_jac(prob, y, lin):
    lin.jac[0, 0] = 0.0
    lin.jac[0, 1] = 1.0
    lin.jac[1, 0] = -2.0 * prob.mu * y[0] * y[1] - 1.0
    lin.jac[1, 1] = prob.mu * (1.0 - y[0] * y[0])


#: Each record's (f, Jacobian).
_FUNCTIONS = {
    LinearProblem: (_linear_f, _linear_jac),
    Kaps: (_kaps_f, _kaps_jac),
    ProtheroRobinson: (_prothero_robinson_f, _prothero_robinson_jac),
    VanDerPol: (_van_der_pol_f, _van_der_pol_jac),
}


def _which(typ):
    if isinstance(typ, types.BaseNamedTuple) and typ.instance_class in _FUNCTIONS:
        return typ.instance_class
    return None


@overload(problems.problem_f, **_OVL)
def _f(prob, y, out):
    if _which(prob) is not None:
        f = _FUNCTIONS[_which(prob)][0]
        return lambda prob, y, out: f(prob, y, out)


@overload(problems.problem_jac, **_OVL)
def _jac(prob, y, lin):
    if _which(prob) is not None:
        jac = _FUNCTIONS[_which(prob)][1]
        return lambda prob, y, lin: jac(prob, y, lin)


@overload(problems.problem_factor, **_OVL)
def _factor(prob, lin, sigma):
    if _which(prob) is not None:
        return lambda prob, lin, sigma: dense_w_factor(sigma, lin.jac, lin.lu, lin.piv)


@overload(problems.problem_solve, **_OVL)
def _solve(prob, lin, b):
    if _which(prob) is not None:
        return lambda prob, lin, b: dense_w_solve(lin.lu, lin.piv, b)


@njit(**_JIT)
def _solve_with(method, prob, y, ws, t_end, rtol, atol, h_fixed, max_steps, abort):
    """``method`` on the driver from y (overwritten) to t_end, in the workspace ``ws``."""
    n = y.size
    lin = DenseLinear(np.zeros((n, n)), np.zeros((n, n)), np.zeros(n, dtype=np.int64))
    obs = PoincareObserver(
        Section(0, True), 0.0, np.empty((0, n)), np.empty(0), np.empty((0, n)), 1.0,
        np.empty(n), np.empty(n), np.zeros(2, dtype=np.int64),
    )  # fmt: skip
    istat = np.zeros(2, dtype=np.int64)
    fstat = np.zeros(1)
    st = drive(
        method, prob, lin, ws, y, t_end,
        Controls(rtol, atol, h_fixed, max_steps), obs, simple_stop(STOP_AT_END, 0, 0), abort,
        istat, fstat,
    )  # fmt: skip
    return st, istat[0], istat[1], fstat[0]


@njit(**ENTRY)
def solve_test_problem(rosenbrock, prob, y0, t_end, rtol, atol, h_fixed, max_steps):
    """Integrate a test problem with Rodas5P (``rosenbrock``) or DOPRI5 on the driver.

    Returns (final state, status, accepted steps, rejected steps, final time).
    ``h_fixed`` > 0 takes fixed steps.
    """
    y = y0.copy()
    abort = np.zeros(1, dtype=np.int64)
    n = y.size
    if rosenbrock:
        st, ns, nr, t = _solve_with(
            RODAS5P_METHOD, prob, y, alloc_workspace(RODAS5P_METHOD, n), t_end, rtol, atol,
            h_fixed, max_steps, abort,
        )  # fmt: skip
    else:
        st, ns, nr, t = _solve_with(
            DOPRI5_METHOD, prob, y, alloc_workspace(DOPRI5_METHOD, n), t_end, rtol, atol,
            h_fixed, max_steps, abort,
        )  # fmt: skip
    return y, st, ns, nr, t


@njit(**ENTRY)
def solve_test_problem_auto(prob, y0, t_end, rtol, atol, max_steps):
    """Integrate a test problem with ``method="auto"`` (:mod:`.autoswitch`) on the driver.

    Returns (final state, status, accepted steps, rejected steps, final time,
    statistics: switches to stiff, to explicit, explicit and Rosenbrock steps accepted, then
    attempted).
    """
    y = y0.copy()
    ws = alloc_workspace(AUTO_METHOD, y.size)
    st, ns, nr, t = _solve_with(
        AUTO_METHOD, prob, y, ws, t_end, rtol, atol, 0.0, max_steps, np.zeros(1, dtype=np.int64)
    )
    stats = ws.flags[N_AUTO_FLAGS - N_AUTO_STATS :].copy()
    return y, st, ns, nr, t, stats
