"""The tangent problem: the model with k tangent vectors (the variational equations), and the
parameter sensitivity.

Its records (:class:`~.problems.StickSlipTangent`, :class:`~.problems.StickSlipTangentSmall`,
:class:`~.problems.ParamSensitivity`) are declared in :mod:`.problems`; this module builds them
and registers their overloads of the generic problem functions, so a kernel that integrates
tangents imports it (:mod:`.variational`, :mod:`stickslip_fast.analysis.lyapunov`).
"""

from __future__ import annotations

import math

import numpy as np
from numba.extending import overload

from ..base.jit import njit
from ..model.equations import (
    jacobian_blocks,
    rhs,
    second_derivative_form_at,
    second_partials_at,
)
from ..model.linalg import (
    bordered_matvec_inline,
    w_solve_inline,
)
from ..model.params import P_ETA, P_ETAP, eta_prime
from . import problems
from .problems import (
    _JIT,
    _OVL,
    ParamSensitivity,
    StickSlip,
    StickSlipSmall,
    StickSlipTangent,
    StickSlipTangentSmall,
    _is,
    factor_w_inline,
    initial_step,
    model_dims,
)

__all__ = ["make_tangent", "make_sensitivity", "tangent_variant"]


@njit(**_JIT)
def make_tangent(
    p: np.ndarray,
    n_osc: int,
    dc: bool,
    n_tangent: int,
    tangent_atol: float,
    p_buf: np.ndarray,
    sens=None,
) -> StickSlipTangent:
    """The tangent problem's record (allocates its small scratch).

    ``sens`` is None for plain tangent vectors, or a :class:`ParamSensitivity`
    (:func:`make_sensitivity`): the last of the ``n_tangent`` vectors is then
    the parameter sensitivity dy/dlambda.
    """
    for i in range(p.size):
        p_buf[i] = p[i]
    p_buf[P_ETAP] = eta_prime(p_buf[P_ETA])
    return StickSlipTangent(
        p_buf, n_osc, dc, n_tangent, tangent_atol,
        np.zeros((n_osc, 4, 4)), np.zeros((n_osc, 4)), np.zeros((n_osc, 4)),
        np.zeros(n_tangent), np.zeros((n_osc, 6)), sens,
    )  # fmt: skip


@njit(**_JIT)
def make_sensitivity(p2: np.ndarray, inv: float, n_osc: int, dc: bool) -> ParamSensitivity:
    """A :class:`ParamSensitivity` from the packed parameters at lambda +- h (2, N_PARAMS).

    ``inv`` is 1 / (the difference of lambda between the two rows); eta' is
    derived from eta in a copy of ``p2``. ``inv`` = 0 makes it inactive: every
    tangent vector is then a plain one, with the plain problem's arithmetic.
    """
    pp = p2.copy()
    for r in range(2):
        pp[r, P_ETAP] = eta_prime(pp[r, P_ETA])
    n = 4 * n_osc + (1 if dc else 0)
    return ParamSensitivity(
        pp, inv, np.zeros((n_osc, 4, 4)), np.zeros((n_osc, 4)), np.zeros((n_osc, 4)),
        np.zeros(1), np.zeros((n_osc, 4, 4)), np.zeros((n_osc, 4)), np.zeros((n_osc, 4)),
        np.zeros((2, n)),
    )  # fmt: skip


def tangent_variant(prob, variant):  # noqa: ARG001 - resolved by overload
    """In compiled code: the tangent record ``prob`` for the kernel variant ``variant``.

    ``variant`` is ``()`` (``prob`` itself, a :class:`StickSlipTangent`) or a
    :func:`small_shape` token (its :class:`StickSlipTangentSmall` twin, sharing
    every array). The caller checks that the token matches N and the belt.
    """


@overload(tangent_variant, **_OVL)
def _tangent_variant(prob, variant):
    if _is(prob, StickSlipTangent):
        if len(variant) == 0:
            return lambda prob, variant: prob

        def impl(prob, variant):
            return StickSlipTangentSmall(
                prob.p, variant, prob.n_tangent, prob.tangent_atol, prob.jb, prob.jcol,
                prob.jrow, prob.unorm, prob.d2, prob.sens,
            )  # fmt: skip

        return impl


# ----------------------------------------- StickSlipTangent and StickSlipTangentSmall
def _is_tangent(prob) -> bool:
    return _is(prob, StickSlipTangent) or _is(prob, StickSlipTangentSmall)


def _tangent_base(prob):  # noqa: ARG001 - resolved by overload
    """The model's record (StickSlip or StickSlipSmall) of a tangent record."""


@overload(_tangent_base, **_OVL)
def _tangent_base_impl(prob):
    if _is(prob, StickSlipTangentSmall):
        return lambda prob: StickSlipSmall(prob.p, prob.shape)
    if _is(prob, StickSlipTangent):
        return lambda prob: StickSlip(prob.p, prob.n_osc, prob.dc)


# ------------------------------------------------- StickSlipTangent(Small), shared
# One body per generic function for both records: the generic record passes its
# run-time N and belt, the small one literals. The arithmetic is the same, so the two
# give bit-identical results. Inside, the J u products, the solves and the
# second-derivative form are inlined (a tangent solve does 1 + k solves and k forms:
# out of line, their call boundaries cost more than their 4x4 arithmetic). The
# bodies themselves are cached functions called out of line: inlined into the
# stepper as well they ran 15 % faster but compiled 2-5x longer (measured: a cold
# find_orbit 65 s against 27 s, a cold Lyapunov run 46 s against 15 s).
@njit(**_JIT)
def _tangent_f(prob, sens, y, out):
    n_osc, dc = model_dims(prob)
    n = 4 * n_osc + (1 if dc else 0)
    k = prob.n_tangent
    rhs(y[:n], prob.p, n_osc, dc, out[:n])
    corner = jacobian_blocks(y[:n], prob.p, n_osc, dc, prob.jb, prob.jcol, prob.jrow)
    for j in range(1, k + 1):
        bordered_matvec_inline(
            prob.jb, prob.jcol, prob.jrow, corner, n_osc, dc,
            y[j * n : (j + 1) * n], out[j * n : (j + 1) * n],
        )  # fmt: skip
    if sens is not None and sens.inv != 0.0:
        # the sensitivity's inhomogeneous term df/dlambda (central difference of f)
        fp = sens.f2[0]
        fm = sens.f2[1]
        rhs(y[:n], sens.p2[0], n_osc, dc, fp)
        rhs(y[:n], sens.p2[1], n_osc, dc, fm)
        for i in range(n):
            out[k * n + i] += (fp[i] - fm[i]) * sens.inv


# Out of line on purpose, like the other bodies: inlined, Numba's dead-code
# elimination dropped its writes through the driver's borrowed records (the d2
# partials went stale: the steps stayed correct but ~50x more of them were needed;
# tests/test_steppers.py checks the step count now).
@njit(**_JIT)
def _tangent_jac(prob, sens, y, lin):
    n_osc, dc = model_dims(prob)
    n = 4 * n_osc + (1 if dc else 0)
    lin.scal[0] = jacobian_blocks(y[:n], prob.p, n_osc, dc, lin.blocks, lin.col, lin.row)
    second_partials_at(y[:n], prob.p, n_osc, dc, prob.d2)
    for i in range(y.size):
        lin.at[i] = y[i]
    if sens is not None and sens.inv != 0.0:
        # dJ/dlambda for the sensitivity's block row
        s = sens.inv
        cp = jacobian_blocks(y[:n], sens.p2[0], n_osc, dc, sens.jb, sens.jcol, sens.jrow)
        cm = jacobian_blocks(y[:n], sens.p2[1], n_osc, dc, sens.mjb, sens.mjcol, sens.mjrow)
        sens.corner[0] = (cp - cm) * s
        for i in range(n_osc):
            for r in range(4):
                for c in range(4):
                    sens.jb[i, r, c] = (sens.jb[i, r, c] - sens.mjb[i, r, c]) * s
                if dc:
                    sens.jcol[i, r] = (sens.jcol[i, r] - sens.mjcol[i, r]) * s
                    sens.jrow[i, r] = (sens.jrow[i, r] - sens.mjrow[i, r]) * s


@njit(**_JIT)
def _tangent_solve(prob, sens, lin, b):
    n_osc, dc = model_dims(prob)
    # [[W, 0], [-H(u_j), W]] x = b: solve the state part, then each tangent part
    n = 4 * n_osc + (1 if dc else 0)
    ky = b[:n]
    w_solve_inline(lin.lu, lin.piv, lin.z, lin.row, lin.scal[1], n_osc, dc, ky)
    hv = lin.hv[:n]
    for j in range(1, prob.n_tangent + 1):
        ku = b[j * n : (j + 1) * n]
        # D^2 f(y0)[u_j, ky] from the partials at y0 that _tangent_jac stored
        second_derivative_form_at(prob.d2, lin.at[j * n : (j + 1) * n], ky, prob.p, n_osc, dc, hv)
        for i in range(n):
            ku[i] += hv[i]
        if sens is not None and sens.inv != 0.0 and j == prob.n_tangent:
            # the sensitivity's row of the exact Jacobian has dJ/dlambda too
            bordered_matvec_inline(sens.jb, sens.jcol, sens.jrow, sens.corner[0], n_osc, dc, ky, hv)
            for i in range(n):
                ku[i] += hv[i]
        w_solve_inline(lin.lu, lin.piv, lin.z, lin.row, lin.scal[1], n_osc, dc, ku)


@njit(**_JIT)
def _tangent_error_norm(prob, sens, err, y0, y1, rtol, atol):
    n_osc, dc = model_dims(prob)
    # y scaled by atol + rtol |y|; u_j by tangent_atol |u_j(t0)| + rtol |u_j|; the
    # sensitivity (from s = 0) by tangent_atol max(|s(t0)|, 1) + rtol |s|
    n = 4 * n_osc + (1 if dc else 0)
    k = prob.n_tangent
    for j in range(1, k + 1):
        un = 0.0
        for r in range(j * n, (j + 1) * n):
            un += y0[r] * y0[r]
        prob.unorm[j - 1] = math.sqrt(un)
    if sens is not None and sens.inv != 0.0:
        prob.unorm[k - 1] = max(prob.unorm[k - 1], 1.0)
    acc = 0.0
    for i in range(n):
        sc = atol + rtol * max(abs(y0[i]), abs(y1[i]))
        e = err[i] / sc
        acc += e * e
        for j in range(1, k + 1):
            q = j * n + i
            sc = prob.tangent_atol * prob.unorm[j - 1] + rtol * max(abs(y0[q]), abs(y1[q]))
            e = err[q] / sc
            acc += e * e
    return math.sqrt(acc * (1.0 / ((1.0 + k) * n)))


# The overloads: the bodies above take N and dc from the record (literals for the small one).
@overload(problems.problem_f, **_OVL)
def _tangent_f_ovl(prob, y, out):
    if _is_tangent(prob):
        return lambda prob, y, out: _tangent_f(prob, prob.sens, y, out)


@overload(problems.problem_jac, **_OVL)
def _tangent_jac_ovl(prob, y, lin):
    if _is_tangent(prob):
        return lambda prob, y, lin: _tangent_jac(prob, prob.sens, y, lin)


@overload(problems.problem_factor, **_OVL)
def _tangent_factor_ovl(prob, lin, sigma):
    if _is_tangent(prob):

        def impl(prob, lin, sigma):
            # the model's W: the tangent blocks share it
            n_osc, dc = model_dims(prob)
            return factor_w_inline(lin, sigma, n_osc, dc)

        return impl


@overload(problems.problem_solve, **_OVL)
def _tangent_solve_ovl(prob, lin, b):
    if _is_tangent(prob):
        return lambda prob, lin, b: _tangent_solve(prob, prob.sens, lin, b)


@overload(problems.problem_error_norm, **_OVL)
def _tangent_error_norm_ovl(prob, err, y0, y1, rtol, atol):
    if _is_tangent(prob):
        return lambda prob, err, y0, y1, rtol, atol: _tangent_error_norm(
            prob, prob.sens, err, y0, y1, rtol, atol
        )


@overload(problems.problem_initial_step, **_OVL)
def _tangent_initial_step_ovl(prob, y, f0, rtol, atol, order, work, fwork):
    if _is_tangent(prob):

        def impl(prob, y, f0, rtol, atol, order, work, fwork):
            # from the state part alone
            n_osc, dc = model_dims(prob)
            n = 4 * n_osc + (1 if dc else 0)
            base = _tangent_base(prob)
            return initial_step(base, y[:n], f0[:n], rtol, atol, order, work[:n], fwork[:n])

        return impl
