"""The disk of ``benchmarks/multirate_bound.py``: one disk against a prescribed belt speed.

A problem record for the engine's generic driver (docs/developing.md, "Adding a
problem"): :class:`PrescribedBelt` integrates z = (x, x', phi, phi', t, r), the disk with
the model's own f and J on a belt at v_b(t), the time (so that the Rosenbrock method sees
an autonomous system) and the motor's response to this disk alone,
T_b r' = -r + beta T_s(x' - v_b, phi'), r = 0 at the window start. v_b(t) is a piecewise
quintic on a uniform grid (:func:`quintic`). W = sigma I - J is block triangular, so a
step factors only the disk's 4 x 4 block. :func:`integrate_disks` runs every disk of a
chain over one window on the driver with Rodas5P.

Compile it into a Numba cache folder of its own (``benchmarks/multirate_bound.py`` does):
the driver's cache index would otherwise name :class:`PrescribedBelt`.
"""

from __future__ import annotations

import math
from collections import namedtuple

import numpy as np
from numba import types
from numba.extending import overload

from stickslip_fast.base.jit import ENTRY, JIT, OVERLOAD, njit
from stickslip_fast.core import problems
from stickslip_fast.core.driver import (
    STOP_AT_END,
    Controls,
    PoincareObserver,
    Section,
    drive,
    simple_stop,
)
from stickslip_fast.core.steppers import RODAS5P_METHOD, alloc_workspace
from stickslip_fast.model.equations import (
    friction,
    friction_factor,
    friction_partials,
    jacobian_blocks,
    rhs,
)
from stickslip_fast.model.linalg import dense_w_factor, lu_solve
from stickslip_fast.model.params import P_C, P_C12, P_EPS, P_ETAP, P_M, P_TB, P_VB

N_STATE = 6  # x, x', phi, phi', t, r

#: The linear workspace of :class:`PrescribedBelt`. W = sigma I - J is block triangular
#: (the time row of J is zero, the quadrature column is zero), so only the disk's 4 x 4
#: block ``blocks[0]`` (the model's ``jacobian_blocks``) is factored (``lu``, ``piv``);
#: ``border_col``/``border_row`` are its unused border, ``jt`` is d f_disk / dt, ``jr``
#: the quadrature's row of J and ``sigma`` holds sigma.
BeltLinear = namedtuple(
    "BeltLinear", ["blocks", "border_col", "border_row", "jt", "jr", "lu", "piv", "sigma"]
)

#: One disk driven by a prescribed belt speed: the model parameters ``p`` (of a constant
#: belt: the model's f and J read the belt speed from ``p[P_VB]``, set to v_b(t) at each
#: call), v_b(t) as a
#: piecewise quintic on a uniform grid (start ``t0``, spacing ``ds``; ``coef[j, k]`` is
#: the coefficient of (t - t_k)^j on [t_k, t_k + ds]) and the weight ``r_scale`` of the
#: motor's response r to the disk (beta; 0: none, as in the oracle).
PrescribedBelt = namedtuple("PrescribedBelt", ["p", "t0", "ds", "coef", "r_scale"])


@njit(inline="always", **JIT)
def belt_speed(prob, t):
    """(v_b, dv_b/dt) at t from the piecewise quintic."""
    c = prob.coef
    u = (t - prob.t0) / prob.ds
    k = min(max(int(math.floor(u)), 0), c.shape[1] - 1)
    s = t - (prob.t0 + k * prob.ds)
    v = ((((c[5, k] * s + c[4, k]) * s + c[3, k]) * s + c[2, k]) * s + c[1, k]) * s + c[0, k]
    dv = ((5.0 * c[5, k] * s + 4.0 * c[4, k]) * s + 3.0 * c[3, k]) * s + 2.0 * c[2, k]
    dv = dv * s + c[1, k]
    return v, dv


def quintic(t, v):
    """The C4 quintic interpolating spline through (t, v), as ``PrescribedBelt.coef``.

    With a C1 cubic Hermite interpolant instead, a disk's controller resolved the jumps of
    its second derivative at the grid points (554 instead of 299 steps per disk in the
    spin-up of the two-disk test below).
    """
    from math import factorial

    from scipy.interpolate import make_interp_spline

    spl = make_interp_spline(t, v, k=5)
    left = t[:-1]
    return np.ascontiguousarray(np.stack([spl(left, nu=j) / factorial(j) for j in range(6)]))


@njit(inline="always", **JIT)
def _belt_f(prob, z, out):
    p = prob.p
    vb, _ = belt_speed(prob, z[4])
    p[P_VB] = vb
    rhs(z, p, 1, False, out)  # the disk: the model's f on a belt at v_b(t)
    out[4] = 1.0
    drive_r = 0.0
    if prob.r_scale != 0.0:  # the oracle needs no motor response
        ts, _ = friction(z[1] - vb, z[3], p[P_EPS], p[P_ETAP])
        drive_r = prob.r_scale * ts
    out[5] = (drive_r - z[5]) / p[P_TB]


@njit(inline="always", **JIT)
def _belt_jac(prob, z, lin):
    p = prob.p
    vb, dvb = belt_speed(prob, z[4])
    p[P_VB] = vb
    jacobian_blocks(z, p, 1, False, lin.blocks, lin.border_col, lin.border_row)
    J = lin.blocks[0]
    # d f / d v_b = -(d f / d x') minus the damping terms, as the slip is x' - v_b
    lin.jt[0] = 0.0
    lin.jt[1] = (-J[1, 1] - p[P_C]) * dvb
    lin.jt[2] = 0.0
    lin.jt[3] = (-J[3, 1] - p[P_C12] / p[P_M]) * dvb
    for j in range(5):
        lin.jr[j] = 0.0
    if prob.r_scale != 0.0:
        _, _, t_v, t_w, _, _ = friction_partials(z[1] - vb, z[3], p[P_EPS], p[P_ETAP])
        e = prob.r_scale / p[P_TB]
        lin.jr[1] = e * t_v
        lin.jr[3] = e * t_w
        lin.jr[4] = -e * t_v * dvb


@njit(inline="always", **JIT)
def _belt_solve(prob, lin, b):
    """Solve W x = b in place, W = sigma I - J block triangular (t first, then the disk, r)."""
    sig = lin.sigma[0]
    xt = b[4] / sig
    for i in range(4):
        b[i] += lin.jt[i] * xt
    lu_solve(lin.lu, lin.piv, b, 0, 4)
    b[4] = xt
    acc = b[5]
    for j in range(5):
        acc += lin.jr[j] * b[j]
    b[5] = acc / (sig + 1.0 / prob.p[P_TB])  # d r' / d r = -1 / T_b


@njit(inline="always", **JIT)
def _belt_factor(lin, sigma):
    lin.sigma[0] = sigma
    return dense_w_factor(sigma, lin.blocks[0], lin.lu, lin.piv)


def _is_belt(typ) -> bool:
    return isinstance(typ, types.BaseNamedTuple) and typ.instance_class is PrescribedBelt


@overload(problems.problem_f, **OVERLOAD)
def _f(prob, y, out):
    if _is_belt(prob):
        return lambda prob, y, out: _belt_f(prob, y, out)


@overload(problems.problem_jac, **OVERLOAD)
def _jac(prob, y, lin):
    if _is_belt(prob):
        return lambda prob, y, lin: _belt_jac(prob, y, lin)


@overload(problems.problem_factor, **OVERLOAD)
def _factor(prob, lin, sigma):
    if _is_belt(prob):
        return lambda prob, lin, sigma: _belt_factor(lin, sigma)


@overload(problems.problem_solve, **OVERLOAD)
def _solve(prob, lin, b):
    if _is_belt(prob):
        return lambda prob, lin, b: _belt_solve(prob, lin, b)


@njit(**ENTRY)
def integrate_disks(p, z, t0, ds, coef, r_scale, h_win, sample_dt, samples, rtol, atol, steps):
    """Integrate every disk ``z[i]`` (in place, shape (N, 6)) over [t0, t0 + h_win].

    Each disk on its own Rodas5P driver run against the belt speed of the grid.
    ``samples[i]`` receives disk i's state every ``sample_dt`` from the window
    start; ``steps[i]`` += (accepted, rejected). Returns the worst status code.
    """
    n_disk = z.shape[0]
    lin = BeltLinear(
        np.zeros((1, 4, 4)), np.zeros((1, 4)), np.zeros((1, 4)), np.zeros(4), np.zeros(5),
        np.zeros((4, 4)), np.zeros(4, dtype=np.int64), np.zeros(1),
    )  # fmt: skip
    ws = alloc_workspace(RODAS5P_METHOD, N_STATE)
    prob = PrescribedBelt(p.copy(), t0, ds, coef, r_scale)
    abort = np.zeros(1, dtype=np.int64)
    istat = np.zeros(2, dtype=np.int64)
    fstat = np.zeros(1)
    worst = 0
    for i in range(n_disk):
        obs = PoincareObserver(
            Section(1, True), 0.0, np.empty((0, N_STATE)), np.empty(0), samples[i],
            sample_dt, np.empty(N_STATE), np.empty(N_STATE), np.zeros(2, dtype=np.int64),
        )  # fmt: skip
        y = z[i]
        st = drive(
            RODAS5P_METHOD, prob, lin, ws, y, h_win, Controls(rtol, atol, 0.0, 10_000_000),
            obs, simple_stop(STOP_AT_END, 0, N_STATE), abort, istat, fstat,
        )  # fmt: skip
        for k in range(obs.counts[1], samples.shape[1]):  # a last sample at t_end lost to rounding
            for j in range(N_STATE):
                samples[i, k, j] = y[j]
        steps[i, 0] += istat[0]
        steps[i, 1] += istat[1]
        worst = max(worst, st)
    return worst


@njit(**ENTRY)
def force_of_disks(samples, vb, eps, etap):
    """S at each grid point from per-disk samples (N, k, 6), at the belt speed ``vb`` they saw."""
    out = np.zeros(samples.shape[1])
    for i in range(samples.shape[0]):
        for k in range(samples.shape[1]):
            v = samples[i, k, 1] - vb[k]
            out[k] += v * friction_factor(v, samples[i, k, 3], eps, etap)
    return out
