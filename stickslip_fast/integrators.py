"""Generic compiled steppers: one explicit Runge-Kutta and one Rosenbrock-Wanner.

Each stepper takes its tableau as arrays (see :mod:`stickslip_fast.tableaus`),
so another tableau of the same family needs no new code. A step writes the new
state and an error estimate and leaves its stages in K. Dense output is kept
apart from stepping: :func:`erk_dense` / :func:`rosenbrock_dense` build its
coefficients from the stages only for steps that need them (a Poincare crossing
or a sample inside the step), and :func:`dense_value` / :func:`dense_state`
evaluate it.

Dense-output kinds
------------------
``DENSE_POLY`` (explicit RK): y(theta) = y0 + sum_r theta^(r+1) D[r].
``DENSE_HERMITE`` (Rosenbrock): y(theta) = (1-theta) y0 + theta (y1 + (1-theta)
(D[0] + theta (D[1] + theta D[2] ...))).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from .linalg import w_factor, w_solve
from .model import jacobian_blocks, rhs

DENSE_POLY = 0
DENSE_HERMITE = 1

_JIT = dict(cache=True, nogil=True)


@njit(**_JIT)
def error_norm(err: np.ndarray, y0: np.ndarray, y1: np.ndarray, rtol: float, atol: float) -> float:
    """RMS norm of err scaled by atol + rtol max(|y0|, |y1|)."""
    n = err.size
    acc = 0.0
    for i in range(n):
        sc = atol + rtol * max(abs(y0[i]), abs(y1[i]))
        e = err[i] / sc
        acc += e * e
    return math.sqrt(acc / n)


@njit(**_JIT)
def initial_step(y0, f0, p, n_osc, dc, rtol, atol, order, work, fwork) -> float:
    """Hairer-Norsett-Wanner's starting step guess (II.4), two RHS evaluations."""
    n = y0.size
    d0 = 0.0
    d1 = 0.0
    for i in range(n):
        sc = atol + rtol * abs(y0[i])
        d0 += (y0[i] / sc) ** 2
        d1 += (f0[i] / sc) ** 2
    d0 = math.sqrt(d0 / n)
    d1 = math.sqrt(d1 / n)
    h0 = 1e-6 if (d0 < 1e-5 or d1 < 1e-5) else 0.01 * d0 / d1
    for i in range(n):
        work[i] = y0[i] + h0 * f0[i]
    rhs(work, p, n_osc, dc, fwork)
    d2 = 0.0
    for i in range(n):
        sc = atol + rtol * abs(y0[i])
        d2 += ((fwork[i] - f0[i]) / sc) ** 2
    d2 = math.sqrt(d2 / n) / h0
    big = max(d1, d2)
    if big <= 1e-15:
        h1 = max(1e-6, h0 * 1e-3)
    else:
        h1 = (0.01 / big) ** (1.0 / (order + 1.0))
    return min(100.0 * h0, h1)


# ------------------------------------------------------------------ step control
# PI controller (Gustafsson; Hairer-Wanner IV.2). q is the order of the error
# estimate plus one. Shared by every adaptive kernel.
STEP_SAFETY = 0.9
STEP_FAC_MIN = 0.2
STEP_FAC_MAX = 6.0
PI_ALPHA = 0.7
PI_BETA = 0.4


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


# --------------------------------------------------------------------------- ERK
@njit(**_JIT)
def erk_step(A, b, b_err, y0, h, p, n_osc, dc, K, ytmp, y1, err) -> None:
    """One explicit RK step (FSAL): K[0] must hold f(y0) on entry.

    On return y1 is the new state, err the embedded error estimate and K[s-1]
    holds f(y1) (FSAL). :func:`erk_dense` turns K into dense output on demand.
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
        rhs(ytmp, p, n_osc, dc, K[st])
    for i in range(n):
        e = 0.0
        for j in range(s):
            e += b_err[j] * K[j, i]
        err[i] = h * e


@njit(**_JIT)
def erk_dense(P, K, h, D) -> None:
    """Dense-output coefficients (DENSE_POLY) of the last :func:`erk_step`: D = h P^T K."""
    s = P.shape[0]
    for r in range(P.shape[1]):
        for i in range(K.shape[1]):
            acc = 0.0
            for j in range(s):
                acc += P[j, r] * K[j, i]
            D[r, i] = h * acc


# -------------------------------------------------------------------- Rosenbrock
@njit(**_JIT)
def rosenbrock_step(
    gamma,
    a,
    C,
    b,
    b_err,
    y0,
    f0,
    h,
    p,
    n_osc,
    dc,
    jb,
    jcol,
    jrow,
    jcorner,
    lu,
    piv,
    z,
    K,
    ytmp,
    ftmp,
    y1,
    err,
) -> bool:
    """One Rosenbrock-Wanner step for an autonomous system (transformed form).

    Solves, with W = I / (h gamma) - J(y0),

        W k_i = f(y0 + sum_{j<i} a_ij k_j) + sum_{j<i} (C_ij / h) k_j

    and sets y1 = y0 + sum_i b_i k_i and err = sum_i b_err_i k_i; the stages
    stay in K for :func:`rosenbrock_dense`. ``f0`` is f(y0); the Jacobian
    (jb, jcol, jrow, jcorner) must have been evaluated at y0. Returns False if W
    is singular or a stage is not finite.
    """
    s = b.size
    n = y0.size
    schur = w_factor(1.0 / (h * gamma), jb, jcol, jrow, jcorner, n_osc, dc, lu, piv, z)
    if not math.isfinite(schur):
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
            rhs(ytmp, p, n_osc, dc, ftmp)
        kst = K[st]
        for i in range(n):
            acc = 0.0
            for j in range(st):
                acc += C[st, j] * K[j, i]
            kst[i] = ftmp[i] + inv_h * acc
        w_solve(lu, piv, z, jrow, schur, n_osc, dc, kst)
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


@njit(**_JIT)
def rosenbrock_dense(H, K, D) -> None:
    """Dense-output coefficients (DENSE_HERMITE) of the last step: D = H K."""
    s = H.shape[1]
    for r in range(H.shape[0]):
        for i in range(K.shape[1]):
            acc = 0.0
            for j in range(s):
                acc += H[r, j] * K[j, i]
            D[r, i] = acc


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
    for i in range(y0.size):
        out[i] = dense_value(kind, theta, y0, y1, D, i)


__all__ = [
    "DENSE_POLY",
    "DENSE_HERMITE",
    "erk_step",
    "erk_dense",
    "rosenbrock_step",
    "rosenbrock_dense",
    "dense_value",
    "dense_state",
    "error_norm",
    "initial_step",
    "rejected_step_factor",
    "accepted_step_factor",
    "jacobian_blocks",
]
