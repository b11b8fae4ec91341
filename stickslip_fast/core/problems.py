"""Problem records: what the generic steppers integrate.

A problem is a small immutable record (a namedtuple) holding its parameters.
The steppers of :mod:`stickslip_fast.core.steppers` call only the generic functions
below, and Numba dispatches them on the record's *type* (``numba.extending.
overload``), so one compiled stepper serves every problem and still lands in
Numba's on-disk cache (passing functions as arguments, or building steppers in
closures, would not).

The generic functions
---------------------
``problem_f(prob, y, out)``
    Right-hand side f(y) into ``out``.
``problem_jac(prob, y, lin)``
    Evaluate the Jacobian at y into the linear workspace ``lin``.
``problem_factor(prob, lin, sigma) -> bool``
    Factor W = sigma I - J; False if W is singular or not finite.
``problem_solve(prob, lin, b)``
    Solve W x = b in place.
``problem_error_norm(prob, err, y0, y1, rtol, atol) -> float``
    The step-size controller's error norm (default: :func:`error_norm`).
``problem_initial_step(prob, y, f0, rtol, atol, order, work, fwork) -> float``
    Starting step (default: :func:`initial_step`).

Records
-------
:class:`StickSlip`
    The paper's model, y' = f(y), with the bordered O(N) linear algebra.
:class:`StickSlipSmall`
    The same model and the same arithmetic with N and the belt kind known at
    compile time (the lengths of two tuple fields): Numba compiles one kernel
    per (N, belt), with constant loop bounds and nothing called out of line,
    about 1.5x faster per step than :class:`StickSlip` for N = 1 and giving
    bit-identical results. The kernels use it for small N (see
    :data:`SMALL_N_MAX`).
:class:`StickSlipTangent`
    The model with ``n_tangent`` tangent vectors, Y = (y, u_1, ..., u_k) with
    u_j' = J(y) u_j (the variational equations: k = 1 for a Lyapunov exponent,
    k = n for the state-transition matrix). Its exact Jacobian is block lower
    triangular, [[J, 0], [H(u_j), J]] with H(u) v = D^2 f(y)[u, v], so W is
    factored once (the model's W) and every solve is a block forward
    substitution. Its error norm scales each u_j by ``tangent_atol |u_j|``:
    a direction's absolute tolerance is relative to its length. With a
    :class:`ParamSensitivity` in its ``sens`` field, the last vector is the
    sensitivity to one parameter, s = dy/dlambda with s' = J s + df/dlambda
    (its Jacobian row gains dJ/dlambda); df/dlambda and dJ/dlambda are central
    differences of the model's f and J in lambda, which have no integration
    error in them.
:class:`StickSlipTangentSmall`
    :class:`StickSlipTangent` with N and the belt kind known at compile time,
    as :class:`StickSlipSmall` is to :class:`StickSlip`: the same arithmetic
    (bit-identical results) with constant loop bounds and the linear algebra
    inlined. The number of tangent vectors stays a run-time value.

Adding a problem: define a namedtuple record, a linear workspace, and an
``overload`` of ``problem_f``, ``problem_jac``, ``problem_factor`` and ``problem_solve``
that tests ``instance_class`` (the error norm and the starting step default; see
:mod:`stickslip_fast.core.testproblems` and docs/developing.md).
"""

from __future__ import annotations

import math
from collections import namedtuple

import numpy as np
from numba import types
from numba.extending import overload

from ..base.jit import JIT, LLVM_INLINED, OVERLOAD, is_record, njit
from ..model.equations import (
    jacobian_blocks,
    rhs,
)
from ..model.linalg import (
    blocks_factor,
    blocks_solve,
    w_factor,
    w_factor_inline,
    w_solve,
    w_solve_inline,
)
from ..model.params import P_ETA, P_ETAP, eta_prime

__all__ = [
    "StickSlip",
    "StickSlipSmall",
    "StickSlipTangent",
    "StickSlipTangentSmall",
    "ParamSensitivity",
    "BorderedLinear",
    "SMALL_N_MAX",
    "make_stickslip",
    "make_small",
    "small_shape",
    "shape_dims",
    "alloc_bordered_linear",
    "problem_f",
    "problem_jac",
    "problem_factor",
    "problem_solve",
    "problem_error_norm",
    "problem_initial_step",
    "error_norm",
    "initial_step",
]


_JIT = JIT


_OVL = OVERLOAD


#: The model. ``p`` is the packed parameter array with eta' filled in.
StickSlip = namedtuple("StickSlip", ["p", "n_osc", "dc"])


#: The model with N and the belt kind known at compile time: ``shape`` is the
#: token :func:`small_shape` makes, whose *type* holds them (N int64 zeros, then
#: a float64 zero for the DC motor).
StickSlipSmall = namedtuple("StickSlipSmall", ["p", "shape"])


#: The model with ``n_tangent`` tangent vectors; ``jb``, ``jcol``, ``jrow`` are
#: scratch for J(y) u inside the right-hand side, ``unorm`` for the error norm,
#: ``d2`` the friction's second partials at the last Jacobian's point (N, 6).
#: ``sens`` is None (plain tangent vectors) or a :class:`ParamSensitivity`: then,
#: unless its ``inv`` is 0 (inactive), the last tangent vector is s = dy/dlambda.
#: The Lyapunov kernel takes None (its plain record compiles without the
#: sensitivity's code); orbits take a record, active or not, so that finding an
#: orbit and continuing it share one compiled kernel (:mod:`.variational`).
StickSlipTangent = namedtuple(
    "StickSlipTangent",
    ["p", "n_osc", "dc", "n_tangent", "tangent_atol", "jb", "jcol", "jrow", "unorm", "d2", "sens"],
)


#: The tangent problem with N and the belt kind known at compile time (``shape``
#: as in :class:`StickSlipSmall`); the other fields as in :class:`StickSlipTangent`.
StickSlipTangentSmall = namedtuple(
    "StickSlipTangentSmall",
    ["p", "shape", "n_tangent", "tangent_atol", "jb", "jcol", "jrow", "unorm", "d2", "sens"],
)


#: The sensitivity s = dy/dlambda to one parameter, s' = J s + df/dlambda, whose
#: row of the exact Jacobian is [H(s) + dJ/dlambda, J]. ``p2`` holds the packed
#: parameters at lambda + h and lambda - h (eta' filled in; one row at lambda itself at
#: the edge of its valid range), ``inv`` = 1 / (their difference in lambda):
#: df/dlambda and dJ/dlambda are central differences of the model's f and J,
#: which carry no integration error. ``jb``, ``jcol``, ``jrow``, ``corner`` hold
#: dJ/dlambda at the last Jacobian's point, ``mjb``, ``mjcol``, ``mjrow`` and
#: ``f2`` (2, n) are scratch.
ParamSensitivity = namedtuple(
    "ParamSensitivity",
    ["p2", "inv", "jb", "jcol", "jrow", "corner", "mjb", "mjcol", "mjrow", "f2"],
)


#: The bordered Jacobian at the last evaluation point and the factors of W.
#: ``scal`` holds (corner, Schur complement); ``at`` the evaluation point and
#: ``hv`` scratch (both used by the tangent problem only).
BorderedLinear = namedtuple(
    "BorderedLinear", ["blocks", "col", "row", "lu", "piv", "z", "scal", "at", "hv"]
)


_is = is_record


@njit(**_JIT)
def make_stickslip(p: np.ndarray, n_osc: int, dc: bool, p_buf: np.ndarray) -> StickSlip:
    """The model's record, with eta' derived from eta into ``p_buf`` (a copy of p)."""
    for i in range(p.size):
        p_buf[i] = p[i]
    p_buf[P_ETAP] = eta_prime(p_buf[P_ETA])
    return StickSlip(p_buf, n_osc, dc)


#: The largest N for which the trajectory kernels compile a :class:`StickSlipSmall`
#: kernel (each (N, belt) pair is one more compiled kernel per entry point).
SMALL_N_MAX = 1


def small_shape(n_osc: int, dc: bool) -> tuple:
    """The compile-time token of a :class:`StickSlipSmall`: ``(0,) * N + (0.0,) * dc``.

    Only its type matters. It is a flat tuple of scalars (the sweep kernels
    used to pass it into ``prange`` bodies, which take tuples of scalars only).
    """
    return (0,) * int(n_osc) + (0.0,) * int(bool(dc))


def shape_dims(shape_type) -> tuple[int, bool]:
    """At compile time: (N, dc) of a :func:`small_shape` token's Numba type."""
    kinds = [t for t in getattr(shape_type, "types", ())]
    n_osc = sum(1 for t in kinds if isinstance(t, types.Integer))
    return n_osc, len(kinds) > n_osc


def _small_dims(prob_type) -> tuple[int, bool]:
    """At compile time: (N, dc) of a :class:`StickSlipSmall` type."""
    return shape_dims(prob_type.types[1])


@njit(**_JIT)
def make_small(prob: StickSlip, shape: tuple) -> StickSlipSmall:
    """The :class:`StickSlipSmall` twin of ``prob`` (same parameter array).

    ``shape`` is ``small_shape(prob.n_osc, prob.dc)``; the caller checks that.
    """
    return StickSlipSmall(prob.p, shape)


@njit(**_JIT)
def alloc_bordered_linear(n_osc: int, n_total: int) -> BorderedLinear:
    """A :class:`BorderedLinear` for N disks and a full state of size ``n_total``."""
    n = 4 * n_osc + 1
    return BorderedLinear(
        np.zeros((n_osc, 4, 4)), np.zeros((n_osc, 4)), np.zeros((n_osc, 4)),
        np.zeros((n_osc, 4, 4)), np.zeros((n_osc, 4), dtype=np.int64), np.zeros((n_osc, 4)),
        np.zeros(2), np.zeros(n_total), np.zeros(n),
    )  # fmt: skip


# ----------------------------------------------------------- default algorithms
@njit(inline="always", **_JIT)
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
def initial_step(prob, y0, f0, rtol, atol, order, work, fwork) -> float:
    """Hairer-Norsett-Wanner's starting step guess (II.4), one more RHS evaluation."""
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
    problem_f(prob, work, fwork)
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


# ------------------------------------------------------------ generic functions
def problem_f(prob, y, out):  # noqa: ARG001 - resolved by overload
    """f(y) into out."""


def problem_jac(prob, y, lin):  # noqa: ARG001
    """Evaluate the Jacobian at y into lin."""


def problem_factor(prob, lin, sigma):  # noqa: ARG001
    """Factor W = sigma I - J; False if singular."""


def problem_solve(prob, lin, b):  # noqa: ARG001
    """Solve W x = b in place."""


def problem_error_norm(prob, err, y0, y1, rtol, atol):  # noqa: ARG001
    """Error norm of a step."""


def problem_initial_step(prob, y, f0, rtol, atol, order, work, fwork):  # noqa: ARG001
    """Starting step size."""


# ------------------------------------------------ StickSlip and StickSlipSmall
# One overload per generic function serves both model records: the small record's
# N and belt kind are compile-time literals (closure constants), the generic
# record's are its fields. For the small record the linear algebra is inlined
# (w_factor_inline / w_solve_inline): called out of line, each of the eight solves
# of a Rodas5P step passed seven arrays across a call boundary and cost more than
# its arithmetic (measured: 2.2 -> 0.83 us per step for N = 1). Inlining the RHS
# as well gained nothing measurable and costs compile time.
def _is_model(prob) -> bool:
    return _is(prob, StickSlip) or _is(prob, StickSlipSmall)


def model_dims(prob):  # noqa: ARG001 - resolved by overload
    """(N, dc) of a model or tangent record: a small record's compile-time literals, or a
    generic record's fields."""


@overload(model_dims, **_OVL)
def _model_dims(prob):
    if _is(prob, StickSlipSmall) or _is(prob, StickSlipTangentSmall):
        n_osc, dc = _small_dims(prob)
        return lambda prob: (n_osc, dc)
    if _is(prob, StickSlip) or _is(prob, StickSlipTangent):
        return lambda prob: (prob.n_osc, prob.dc)


def _factor_into(w_factor_fn):
    """W = sigma I - J by ``w_factor_fn`` into ``lin``, keeping the Schur complement."""

    def factor(lin, sigma, n_osc, dc):
        schur = w_factor_fn(
            sigma, lin.blocks, lin.col, lin.row, lin.scal[0], n_osc, dc, lin.lu, lin.piv, lin.z
        )
        lin.scal[1] = schur
        return math.isfinite(schur)

    return factor


#: ``factor_w(lin, sigma, n_osc, dc) -> bool``: the model's W into ``lin`` (called
#: linear algebra), ``factor_w_inline`` the same with it inlined (small records).
factor_w = njit(inline="always", **_JIT)(_factor_into(w_factor))
factor_w_inline = njit(inline="always", **_JIT)(_factor_into(w_factor_inline))
#: The blocks' LU and solve of a small record without a DC motor (W has no border),
#: compiled once and inlined by LLVM (``forceinline``), not at the Numba IR level: a
#: Rodas5P step solves eight times, and Numba typed and lowered eight IR copies of
#: the solve in the step, and each again in the overload's typing-only compile (a
#: first ``simulate``: the step 0.85 s instead of 1.6-2.0 s, exclusive; docs/
#: performance.md, "The first run"). LLVM inlines it with the same constant N; warm,
#: method="auto" measured 10-17 % faster and Rodas5P at eta = 2.0 ~2 % slower, with
#: bit-identical results. (The DC-motor path's W, treated so, was slower: not kept.)
#: Uncached (LLVM_INLINED): a cached copy would share ``blocks_factor``'s cache entries.
_blocks_factor_call = njit(**LLVM_INLINED)(blocks_factor.py_func)
_blocks_solve_call = njit(**LLVM_INLINED)(blocks_solve.py_func)


@overload(problem_f, **_OVL)
def _model_f(prob, y, out):
    if _is_model(prob):

        def impl(prob, y, out):
            n_osc, dc = model_dims(prob)
            rhs(y, prob.p, n_osc, dc, out)

        return impl


@overload(problem_jac, **_OVL)
def _model_jac(prob, y, lin):
    if _is_model(prob):

        def impl(prob, y, lin):
            n_osc, dc = model_dims(prob)
            lin.scal[0] = jacobian_blocks(y, prob.p, n_osc, dc, lin.blocks, lin.col, lin.row)

        return impl


@overload(problem_factor, **_OVL)
def _model_factor(prob, lin, sigma):
    if _is(prob, StickSlipSmall):
        n_osc, dc = _small_dims(prob)
        if not dc:
            # the blocks alone: W has no border
            return lambda prob, lin, sigma: _blocks_factor_call(
                sigma, lin.blocks, n_osc, lin.lu, lin.piv
            )
        return lambda prob, lin, sigma: factor_w_inline(lin, sigma, n_osc, dc)
    if _is(prob, StickSlip):
        return lambda prob, lin, sigma: factor_w(lin, sigma, prob.n_osc, prob.dc)


@overload(problem_solve, **_OVL)
def _model_solve(prob, lin, b):
    if _is(prob, StickSlipSmall):
        n_osc, dc = _small_dims(prob)
        if not dc:
            return lambda prob, lin, b: _blocks_solve_call(lin.lu, lin.piv, b, n_osc)
        return lambda prob, lin, b: w_solve_inline(
            lin.lu, lin.piv, lin.z, lin.row, lin.scal[1], n_osc, dc, b
        )
    if _is(prob, StickSlip):
        return lambda prob, lin, b: w_solve(
            lin.lu, lin.piv, lin.z, lin.row, lin.scal[1], prob.n_osc, prob.dc, b
        )


# ------------------------------------------------------------------- defaults
# A record that does not overload these gets the default algorithms (the model and
# the test problems); the tangent records bring their own (core/tangent.py).
def _takes_defaults(prob) -> bool:
    return isinstance(prob, types.BaseNamedTuple) and not (
        _is(prob, StickSlipTangent) or _is(prob, StickSlipTangentSmall)
    )


@overload(problem_error_norm, **_OVL)
def _default_error_norm(prob, err, y0, y1, rtol, atol):
    if _takes_defaults(prob):
        return lambda prob, err, y0, y1, rtol, atol: error_norm(err, y0, y1, rtol, atol)


@overload(problem_initial_step, **_OVL)
def _default_initial_step(prob, y, f0, rtol, atol, order, work, fwork):
    if _takes_defaults(prob):

        def impl(prob, y, f0, rtol, atol, order, work, fwork):
            return initial_step(prob, y, f0, rtol, atol, order, work, fwork)

        return impl
