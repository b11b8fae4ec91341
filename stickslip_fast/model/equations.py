"""The paper's model: smooth Contensou-Pade friction, right-hand side, analytic Jacobian.

This module is the single source of the equations: the right-hand side, its
Jacobian and its second derivative. Every problem (:mod:`stickslip_fast.core.problems`)
and every kernel calls it.

State layout (see :attr:`System.state_names`): disk i occupies slots
``4 i .. 4 i + 3`` as (x_i, dx_i, phi_i, dphi_i); the DC motor's belt speed v_b
is the last slot. Per disk (paper Eq. 15, nondimensional)::

    x''   = -(c x' + c12 phi') - (x + k12 phi) - mu T_s(x' - v_b, phi', eps)
    m phi'' = -(c12 x' + c phi') - (k12 x + phi) - mu M_s(x' - v_b, phi', eps)
    T_b v_b' = v_b0 - v_b + (beta / N) sum_i T_s(x_i' - v_b, phi_i', eps)   (DC motor)

The Jacobian is stored in bordered block-diagonal form: N dense 4x4 blocks,
plus (DC motor only) a border column d f_i / d v_b, a border row
d f_vb / d y_i and a corner d f_vb / d v_b. See :mod:`stickslip_fast.model.linalg`.
"""

from __future__ import annotations

import math

import numpy as np

from ..base.jit import ENTRY, JIT, njit
from .linalg import bordered_matvec
from .params import (
    P_BETA,
    P_C,
    P_C12,
    P_EPS,
    P_ETAP,
    P_K12,
    P_M,
    P_MU,
    P_TB,
    P_VB,
    P_VB0,
    eta_prime,
)

__all__ = [
    "eta_prime",
    "friction",
    "friction_factor",
    "friction_partials",
    "friction_second_partials",
    "rest_position",
    "rhs",
    "jacobian_blocks",
    "jacobian_vector",
    "second_derivative_form",
    "second_partials_at",
    "second_derivative_form_at",
    "tangent_rhs",
    "dense_jacobian",
]

# error_model="numpy": a division by zero gives inf/nan instead of raising, so no
# parameter value can make compiled (possibly parallel) code raise.
_JIT = JIT


@njit(**_JIT)
def friction_factor(v: float, w: float, eps: float, etap: float) -> float:
    """The common factor g = s^(-1/2) + eta' eps^3 / s^2 of T_s and M_s, s = v^2 + w^2 + eps^2.

    Written as sqrt(s) / s + eta' eps^3 (1/s)^2 so that the square root and the one
    division run side by side: an integration's steps wait on this value, and
    1 / sqrt(s) would put the two long latencies one after the other.
    """
    s = v * v + w * w + eps * eps
    inv_s = 1.0 / s
    return math.sqrt(s) * inv_s + etap * eps * eps * eps * (inv_s * inv_s)


@njit(**_JIT)
def friction(v: float, w: float, eps: float, etap: float) -> tuple[float, float]:
    """Friction force T_s and torque M_s for slip velocity v and spin w.

    T_s = v g, M_s = (2/3) w g with g = s^(-1/2) + eta' eps^3 / s^2 and
    s = v^2 + w^2 + eps^2 (the paper's Eq. 2; g from :func:`friction_factor`).
    """
    g = friction_factor(v, w, eps, etap)
    return v * g, (2.0 / 3.0) * w * g


@njit(**_JIT)
def friction_partials(v: float, w: float, eps: float, etap: float):
    """T_s, M_s and their partial derivatives (T_v, T_w, M_v, M_w).

    With h = dg/ds * 2 = -s^(-3/2) - 4 eta' eps^3 / s^3, dg/dv = v h and dg/dw = w h.
    """
    s = v * v + w * w + eps * eps
    inv_s = 1.0 / s  # beside the square root, as in friction_factor (the same g, bit for bit)
    inv_sqrt = math.sqrt(s) * inv_s
    e3 = etap * eps * eps * eps
    inv_s2 = inv_s * inv_s
    g = inv_sqrt + e3 * inv_s2
    h = -inv_sqrt * inv_s - 4.0 * e3 * (inv_s2 * inv_s)
    t = v * g
    mm = (2.0 / 3.0) * w * g
    t_v = g + v * v * h
    t_w = v * w * h
    m_v = (2.0 / 3.0) * w * v * h
    m_w = (2.0 / 3.0) * (g + w * w * h)
    return t, mm, t_v, t_w, m_v, m_w


@njit(**_JIT)
def friction_second_partials(v: float, w: float, eps: float, etap: float):
    """Second partial derivatives of T_s and M_s w.r.t. slip v and spin w.

    Returns (T_vv, T_vw, T_ww, M_vv, M_vw, M_ww). With s = v^2 + w^2 + eps^2,
    g = s^(-1/2) + eta' eps^3 s^(-2), h = 2 dg/ds = -s^(-3/2) - 4 eta' eps^3 s^(-3)
    (as in :func:`friction_partials`) and q = 2 dh/ds = 3 s^(-5/2) + 24 eta' eps^3 s^(-4),
    so that dg/dv = v h, dh/dv = v q (likewise for w)::

        T_vv = 3 v h + v^3 q          M_vv = (2/3) (w h + v^2 w q)
        T_vw = w h + v^2 w q          M_vw = (2/3) (v h + v w^2 q)
        T_ww = v h + v w^2 q          M_ww = (2/3) (3 w h + w^3 q)

    Used by the variational equations (:mod:`stickslip_fast.analysis`), whose
    Jacobian needs d(J(y) u)/dy.
    """
    s = v * v + w * w + eps * eps
    inv_sqrt = 1.0 / math.sqrt(s)
    inv_s = 1.0 / s
    e3 = etap * eps * eps * eps
    inv_s3 = inv_s * inv_s * inv_s
    h = -inv_sqrt * inv_s - 4.0 * e3 * inv_s3
    q = 3.0 * inv_sqrt * inv_s * inv_s + 24.0 * e3 * inv_s3 * inv_s
    vq = v * q
    wq = w * q
    t_vv = 3.0 * v * h + v * v * vq
    t_vw = w * h + v * v * wq
    t_ww = v * h + v * w * wq
    two3 = 2.0 / 3.0
    m_vv = two3 * (w * h + v * v * wq)
    m_vw = two3 * (v * h + v * w * wq)
    m_ww = two3 * (3.0 * w * h + w * w * wq)
    return t_vv, t_vw, t_ww, m_vv, m_vw, m_ww


@njit(inline="always", **_JIT)  # inlined into its callers: no compile of its own
def rest_position(vb: float, p: np.ndarray) -> tuple[float, float]:
    """(x, phi) of a disk at rest on a belt running at ``vb``: its springs balance the friction.

    With x' = phi' = 0 the slip velocity is -v_b and the spin 0, so M_s = 0 and the
    equations above reduce to x + k12 phi = mu v_b g(-v_b, 0) and k12 x + phi = 0. Every
    disk of a system has this rest position (they share their parameters). NaN for
    |k12| = 1, where the springs hold no unique position.
    """
    k12 = p[P_K12]
    det = 1.0 - k12 * k12
    if det == 0.0:
        return math.nan, math.nan
    x = p[P_MU] * vb * friction_factor(-vb, 0.0, p[P_EPS], p[P_ETAP]) / det
    return x, -k12 * x


@njit(inline="always", **_JIT)
def _coefficients(y: np.ndarray, p: np.ndarray, n_osc: int, dc: bool):
    """(m, k12, c, c12, mu, eps, eta', v_b): the slots f and its Jacobian read, and the belt
    speed at y (the motor's state, or the constant belt's parameter)."""
    vb = y[4 * n_osc] if dc else p[P_VB]
    return p[P_M], p[P_K12], p[P_C], p[P_C12], p[P_MU], p[P_EPS], p[P_ETAP], vb


@njit(**_JIT)
def rhs(y: np.ndarray, p: np.ndarray, n_osc: int, dc: bool, dydt: np.ndarray) -> None:
    """Write dy/dt into ``dydt`` (no allocation).

    Arranged for latency: an explicit stage waits on the previous one's f, so the
    friction factor g is the last value each component waits for (one product and
    one difference after it) and no division follows it (1/m and 1/T_b are
    reciprocals of parameters, ready early).
    """
    m, k12, c, c12, mu, eps, etap, vb = _coefficients(y, p, n_osc, dc)
    inv_m = 1.0 / m
    mu_m = (2.0 / 3.0) * mu * inv_m
    t_sum = 0.0
    for i in range(n_osc):
        j = 4 * i
        x = y[j]
        dx = y[j + 1]
        ph = y[j + 2]
        dph = y[j + 3]
        v = dx - vb
        g = friction_factor(v, dph, eps, etap)
        t_sum += v * g  # T_s
        dydt[j] = dx
        dydt[j + 1] = (-(c * dx + c12 * dph) - (x + k12 * ph)) - (mu * v) * g
        dydt[j + 2] = dph
        dydt[j + 3] = (-(c12 * dx + c * dph) - (k12 * x + ph)) * inv_m - (mu_m * dph) * g
    if dc:
        dydt[4 * n_osc] = (p[P_VB0] - vb + p[P_BETA] / n_osc * t_sum) * (1.0 / p[P_TB])


@njit(**_JIT)
def jacobian_blocks(
    y: np.ndarray,
    p: np.ndarray,
    n_osc: int,
    dc: bool,
    blocks: np.ndarray,
    border_col: np.ndarray,
    border_row: np.ndarray,
) -> float:
    """Analytic Jacobian in bordered block-diagonal form.

    Fills ``blocks`` (N, 4, 4) with d f_i / d y_i and, for the DC motor,
    ``border_col`` (N, 4) with d f_i / d v_b and ``border_row`` (N, 4) with
    d f_vb / d y_i. Returns the corner d f_vb / d v_b (0.0 for a constant belt).
    """
    m, k12, c, c12, mu, eps, etap, vb = _coefficients(y, p, n_osc, dc)
    inv_m = 1.0 / m
    corner = 0.0
    if dc:
        inv_tb = 1.0 / p[P_TB]
        bn = p[P_BETA] / n_osc * inv_tb
        corner = -inv_tb
    for i in range(n_osc):
        j = 4 * i
        _, _, t_v, t_w, m_v, m_w = friction_partials(y[j + 1] - vb, y[j + 3], eps, etap)
        b = blocks[i]
        b[0, 0] = 0.0
        b[0, 1] = 1.0
        b[0, 2] = 0.0
        b[0, 3] = 0.0
        b[1, 0] = -1.0
        b[1, 1] = -c - mu * t_v
        b[1, 2] = -k12
        b[1, 3] = -c12 - mu * t_w
        b[2, 0] = 0.0
        b[2, 1] = 0.0
        b[2, 2] = 0.0
        b[2, 3] = 1.0
        b[3, 0] = -k12 * inv_m
        b[3, 1] = (-c12 - mu * m_v) * inv_m
        b[3, 2] = -inv_m
        b[3, 3] = (-c - mu * m_w) * inv_m
        if dc:
            # slip velocity is dx - vb, so d/dvb = -d/d(dx)
            border_col[i, 0] = 0.0
            border_col[i, 1] = mu * t_v
            border_col[i, 2] = 0.0
            border_col[i, 3] = mu * m_v * inv_m
            border_row[i, 0] = 0.0
            border_row[i, 1] = bn * t_v
            border_row[i, 2] = 0.0
            border_row[i, 3] = bn * t_w
            corner -= bn * t_v
    return corner


@njit(**_JIT)
def jacobian_vector(
    y: np.ndarray,
    u: np.ndarray,
    p: np.ndarray,
    n_osc: int,
    dc: bool,
    blocks: np.ndarray,
    border_col: np.ndarray,
    border_row: np.ndarray,
    out: np.ndarray,
) -> None:
    """Write J(y) u into ``out``, with J from :func:`jacobian_blocks`.

    ``blocks``, ``border_col`` and ``border_row`` are scratch arrays of the
    shapes :func:`jacobian_blocks` fills; they hold J(y) on return.
    """
    corner = jacobian_blocks(y, p, n_osc, dc, blocks, border_col, border_row)
    bordered_matvec(blocks, border_col, border_row, corner, n_osc, dc, u, out)


@njit(inline="always", **_JIT)
def _d2_disk(t_vv, t_vw, t_ww, m_vv, m_vw, m_ww, a1, b1, a2, b2):
    """One disk's (D^2 T_s, D^2 M_s)[(a1, b1), (a2, b2)] in (slip, spin)."""
    cross = a1 * b2 + b1 * a2
    d2t = t_vv * a1 * a2 + t_vw * cross + t_ww * b1 * b2
    d2m = m_vv * a1 * a2 + m_vw * cross + m_ww * b1 * b2
    return d2t, d2m


@njit(**ENTRY)
def second_derivative_form(
    y: np.ndarray,
    u: np.ndarray,
    v: np.ndarray,
    p: np.ndarray,
    n_osc: int,
    dc: bool,
    out: np.ndarray,
) -> None:
    """Write the symmetric bilinear form D^2 f(y)[u, v] into ``out``.

    This is H(y, u) v = d/ds [J(y + s v) u] at s = 0, the lower-left block of the
    Jacobian of the variational system. Only the friction terms are nonlinear,
    so only the dx, dphi (and v_b) rows are nonzero. (Allocates; the tangent
    problem uses :func:`second_partials_at` once per step and
    :func:`second_derivative_form_at` per (u, v).)
    """
    d2 = np.empty((n_osc, 6))
    second_partials_at(y, p, n_osc, dc, d2)
    second_derivative_form_at(d2, u, v, p, n_osc, dc, out)


@njit(**_JIT)
def second_partials_at(y: np.ndarray, p: np.ndarray, n_osc: int, dc: bool, d2: np.ndarray) -> None:
    """Each disk's :func:`friction_second_partials` at y into ``d2`` (N, 6).

    With :func:`second_derivative_form_at` this is :func:`second_derivative_form`
    (bit for bit) for many (u, v) at one y: the tangent problem's solves need k
    forms per stage at the step's start.
    """
    eps = p[P_EPS]
    etap = p[P_ETAP]
    vb = y[4 * n_osc] if dc else p[P_VB]
    for i in range(n_osc):
        j = 4 * i
        t_vv, t_vw, t_ww, m_vv, m_vw, m_ww = friction_second_partials(
            y[j + 1] - vb, y[j + 3], eps, etap
        )
        d2[i, 0] = t_vv
        d2[i, 1] = t_vw
        d2[i, 2] = t_ww
        d2[i, 3] = m_vv
        d2[i, 4] = m_vw
        d2[i, 5] = m_ww


@njit(inline="always", **_JIT)
def second_derivative_form_at(
    d2: np.ndarray,
    u: np.ndarray,
    v: np.ndarray,
    p: np.ndarray,
    n_osc: int,
    dc: bool,
    out: np.ndarray,
) -> None:
    """:func:`second_derivative_form` from the partials of :func:`second_partials_at`."""
    mu = p[P_MU]
    inv_m = 1.0 / p[P_M]
    uvb = u[4 * n_osc] if dc else 0.0
    vvb = v[4 * n_osc] if dc else 0.0
    acc = 0.0
    for i in range(n_osc):
        j = 4 * i
        d2t, d2m = _d2_disk(
            d2[i, 0], d2[i, 1], d2[i, 2], d2[i, 3], d2[i, 4], d2[i, 5],
            u[j + 1] - uvb, u[j + 3], v[j + 1] - vvb, v[j + 3],
        )  # fmt: skip
        out[j] = 0.0
        out[j + 1] = -mu * d2t
        out[j + 2] = 0.0
        out[j + 3] = -mu * d2m * inv_m
        acc += d2t
    if dc:
        out[4 * n_osc] = p[P_BETA] / n_osc * acc / p[P_TB]


@njit(**ENTRY)
def tangent_rhs(
    y: np.ndarray,
    u: np.ndarray,
    p: np.ndarray,
    n_osc: int,
    dc: bool,
    dydt: np.ndarray,
    dudt: np.ndarray,
) -> None:
    """Write f(y) into ``dydt`` and J(y) u into ``dudt`` (allocates scratch; for tests)."""
    rhs(y, p, n_osc, dc, dydt)
    blocks = np.empty((n_osc, 4, 4))
    col = np.zeros((n_osc, 4))
    row = np.zeros((n_osc, 4))
    jacobian_vector(y, u, p, n_osc, dc, blocks, col, row, dudt)


@njit(**ENTRY)
def dense_jacobian(y: np.ndarray, p: np.ndarray, n_osc: int, dc: bool) -> np.ndarray:
    """The full (n_state, n_state) Jacobian, assembled from :func:`jacobian_blocks`.

    For tests and for external solvers; the integrators never form it.
    """
    n = y.size
    blocks = np.empty((n_osc, 4, 4))
    col = np.zeros((n_osc, 4))
    row = np.zeros((n_osc, 4))
    corner = jacobian_blocks(y, p, n_osc, dc, blocks, col, row)
    jac = np.zeros((n, n))
    for i in range(n_osc):
        j = 4 * i
        jac[j : j + 4, j : j + 4] = blocks[i]
        if dc:
            jac[j : j + 4, n - 1] = col[i]
            jac[n - 1, j : j + 4] = row[i]
    if dc:
        jac[n - 1, n - 1] = corner
    return jac
