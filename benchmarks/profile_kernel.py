"""Where the engine's Rodas5P time goes, and what cheaper kernels would buy (issue 11, part 2).

Three measurements, one core, asymmetric preset, constant belt, eta = 2.0 and 9.99,
t_end 1500 (points after 1000):

1. Engine totals from the public API: wall time per attempted step, steps, rejected
   fraction at rtol 1e-6 ... 1e-9 (atol = 0.01 rtol).
2. Cost of each ingredient of a step, timed in ``@njit`` loops of 10^5..10^6 calls:
   the engine's own ``model.rhs``, ``model.jacobian_blocks``, ``linalg.w_factor`` /
   ``w_solve``, ``integrators.error_norm`` (with their current signatures; skipped
   with a note if the rewrite changed them) next to a plain 4-state version
   (:func:`benchmarks.peers.rhs1`, an unrolled dense 4x4 LU). The sum over one
   Rodas5P attempt (7 stage RHS + 1 RHS at the new point, 1 Jacobian, 1 factor,
   8 solves, norm + controller) against the measured cost per attempt gives the
   share of bookkeeping.
3. A replica driver (:func:`rb_integrate`): the same Rodas5P tableau (from
   ``stickslip_fast.core.tableaus``, as data), the same PI controller constants, dense
   4x4 arithmetic and nothing else; its step log classifies every attempt as near a
   stick-slip transition or not. The same driver runs ROS34PW2 (Rang & Angermann
   2005, 4-stage W-method of order 3; coefficients converted to the transformed form
   here) with the Jacobian refreshed every 1, 3 or 10 accepted steps, and Rodas5P
   with a controller that predicts the step after a rejection from the error ratio
   of the two attempts. Its points (cubic Hermite on the step ends) are compared
   with the cached SciPy Radau reference, so each variant is a work-precision
   point, not just a step count.
"""

from __future__ import annotations

import math
import os
import time

import numpy as np
from numba import njit

# the engine's own step-size controller, so that replica and engine take the same steps
from stickslip_fast.core.steppers import PI_ALPHA, PI_BETA
from stickslip_fast.core.steppers import STEP_FAC_MAX as FAC_MAX
from stickslip_fast.core.steppers import STEP_FAC_MIN as FAC_MIN
from stickslip_fast.core.steppers import STEP_SAFETY as SAFETY

from . import peers
from .common import ssf
from .reference import trajectory_reference

ATOL_FACTOR = 1e-2
STICK_V = 1e-3  # |dx1 - v_b| below this (100 eps) counts as sticking
NEAR = 0.05  # an attempt within this time of a stick<->slip switch is "at a transition"


# ------------------------------------------------------------------- tableaus
def rodas5p():
    """(gamma, A, C, M, E, q) of the engine's Rodas5P, transformed form, E = M - M_hat."""
    from stickslip_fast.core.tableaus import RODAS5P as R

    return (
        float(R.gamma), np.asarray(R.a, float), np.asarray(R.C, float), np.asarray(R.b, float),
        np.asarray(R.b_err, float), float(R.embedded_order + 1),
    )  # fmt: skip


def ros34pw2():
    """ROS34PW2 (Rang & Angermann, BIT 45, 2005) converted to the transformed form.

    Standard form: k_i = h f(y0 + sum a_ij k_j) + h J sum g_ij k_j, with Gamma = g + gamma I.
    Transformed (Hairer-Wanner IV.7): A_t = alpha Gamma^-1, C = diag(1/gamma) - Gamma^-1,
    m = b Gamma^-1, and the stages u_i = sum Gamma_ij k_j solve
    (I/(h gamma) - J) u_i = f(y0 + sum A_t,ij u_j) + sum (C_ij / h) u_j.
    """
    g = 4.3586652150845900e-01
    alpha = np.array(
        [
            [0, 0, 0, 0],
            [8.7173304301691801e-01, 0, 0, 0],
            [8.4457060015369423e-01, -1.1299064236484185e-01, 0, 0],
            [0, 0, 1, 0],
        ],
        float,
    )
    gam = np.array(
        [
            [g, 0, 0, 0],
            [-8.7173304301691801e-01, g, 0, 0],
            [-9.0338057013044082e-01, 5.4180672388095326e-02, g, 0],
            [2.4212380706095346e-01, -1.2232505839045147, 5.4526025533510214e-01, g],
        ],
        float,
    )
    b = np.array([2.4212380706095346e-01, -1.2232505839045147, 1.5452602553351020, g])
    bh = np.array([3.7810903145819369e-01, -9.6042292212423178e-02, 0.5, 2.1793326075422950e-01])
    gi = np.linalg.inv(gam)
    A = alpha @ gi
    C = np.diag(np.full(4, 1.0 / g)) - gi
    M = b @ gi
    E = (b - bh) @ gi
    return g, A, C, M, E, 3.0


# ---------------------------------------------------------------- dense 4x4
@njit(cache=True)
def lu4(a, piv):
    for k in range(4):
        p = k
        big = abs(a[k, k])
        for r in range(k + 1, 4):
            if abs(a[r, k]) > big:
                big = abs(a[r, k])
                p = r
        piv[k] = p
        if big == 0.0:
            return False
        if p != k:
            for q in range(4):
                a[k, q], a[p, q] = a[p, q], a[k, q]
        inv = 1.0 / a[k, k]
        for r in range(k + 1, 4):
            a[r, k] *= inv
            f = a[r, k]
            for q in range(k + 1, 4):
                a[r, q] -= f * a[k, q]
    return True


@njit(cache=True)
def lu4_solve(a, piv, b):
    for k in range(4):
        p = piv[k]
        if p != k:
            b[k], b[p] = b[p], b[k]
    for k in range(4):
        s = b[k]
        for q in range(k):
            s -= a[k, q] * b[q]
        b[k] = s
    for k in range(3, -1, -1):
        s = b[k]
        for q in range(k + 1, 4):
            s -= a[k, q] * b[q]
        b[k] = s / a[k, k]


# ------------------------------------------------------------- replica driver
@njit(cache=True)
def rb_integrate(gamma, A, C, M, E, q, p, t_end, t_min, rtol, atol, jac_every, predict, log):
    """Rosenbrock integration of the one-disk problem from rest with dense 4x4 algebra.

    Returns (n_accepted, n_rejected, n_jacobians, n_log, t_points, points). ``log`` rows
    (t, h, accepted, dx1 - v_b at the step start) for the first len(log) attempts.
    ``jac_every`` = k refreshes J every k accepted steps (k > 1 only for W-methods).
    ``predict`` = True: after a rejection the next rejection factor uses the error
    ratio of the two attempts (estimates the local order) instead of the nominal q.
    """
    s = M.size
    y = np.zeros(4)
    y1 = np.empty(4)
    ytmp = np.empty(4)
    f0 = np.empty(4)
    f1 = np.empty(4)
    K = np.empty((s, 4))
    J = np.empty((4, 4))
    W = np.empty((4, 4))
    piv = np.empty(4, np.int64)
    tp = np.empty(100_000)
    pts = np.empty((100_000, 4))
    npts = 0
    rhs1(y, p, f0)
    # Hairer's initial step
    d0 = 0.0
    d1 = 0.0
    for i in range(4):
        sc = atol + rtol * abs(y[i])
        d0 += (y[i] / sc) ** 2
        d1 += (f0[i] / sc) ** 2
    d0 = math.sqrt(d0 / 4)
    d1 = math.sqrt(d1 / 4)
    h = 1e-6 if (d0 < 1e-5 or d1 < 1e-5) else 0.01 * d0 / d1
    t = 0.0
    n_acc = 0
    n_rej = 0
    n_jac = 0
    n_log = 0
    since_jac = jac_every
    err_prev = 1.0
    last_rej = False
    en_rej = 0.0
    h_rej = 0.0
    while t < t_end:
        if t + 1.01 * h >= t_end:
            h = t_end - t
        if since_jac >= jac_every:
            jac1(y, p, J)
            n_jac += 1
            since_jac = 0
        sig = 1.0 / (h * gamma)
        for i in range(4):
            for j in range(4):
                W[i, j] = -J[i, j]
            W[i, i] += sig
        ok = lu4(W, piv)
        inv_h = 1.0 / h
        for st in range(s):
            if st == 0:
                for i in range(4):
                    f1[i] = f0[i]
            else:
                for i in range(4):
                    acc = 0.0
                    for j in range(st):
                        acc += A[st, j] * K[j, i]
                    ytmp[i] = y[i] + acc
                rhs1(ytmp, p, f1)
            for i in range(4):
                acc = 0.0
                for j in range(st):
                    acc += C[st, j] * K[j, i]
                K[st, i] = f1[i] + inv_h * acc
            lu4_solve(W, piv, K[st])
        en = 0.0
        for i in range(4):
            acc = 0.0
            e = 0.0
            for j in range(s):
                acc += M[j] * K[j, i]
                e += E[j] * K[j, i]
            y1[i] = y[i] + acc
            sc = atol + rtol * max(abs(y[i]), abs(y1[i]))
            en += (e / sc) ** 2
        en = math.sqrt(en / 4)
        if n_log < log.shape[0]:
            log[n_log, 0] = t
            log[n_log, 1] = h
            log[n_log, 2] = 1.0 if (ok and en <= 1.0) else 0.0
            log[n_log, 3] = y[1] - p[7]
            n_log += 1
        if not ok or not math.isfinite(en) or en > 1.0:
            n_rej += 1
            if not math.isfinite(en) or not ok:
                fac = 0.25
            else:
                qq = q
                if predict and last_rej and en_rej > 1.0 and en > 1.0 and h_rej > h:
                    # observed order from two rejected attempts: en ~ h^k
                    k = math.log(en_rej / en) / math.log(h_rej / h)
                    qq = min(q, max(1.0, k))
                fac = max(FAC_MIN, SAFETY * en ** (-1.0 / qq))
            en_rej = en
            h_rej = h
            h *= fac
            last_rej = True
            continue
        rhs1(y1, p, f1)
        if y[1] < 0.0 <= y1[1] and t + h >= t_min and npts < tp.size:
            # cubic Hermite on the step ends, safeguarded Newton on component 1
            a1 = y[1]
            b1 = y1[1]
            lo = 0.0
            hi = 1.0
            th = a1 / (a1 - b1)
            for _ in range(50):
                t2 = th * th
                t3 = t2 * th
                g = (
                    (2 * t3 - 3 * t2 + 1) * a1 + (t3 - 2 * t2 + th) * h * f0[1]
                    + (-2 * t3 + 3 * t2) * b1 + (t3 - t2) * h * f1[1]
                )  # fmt: skip
                if g < 0.0:
                    lo = th
                else:
                    hi = th
                dg = (
                    (6 * t2 - 6 * th) * a1 + (3 * t2 - 4 * th + 1) * h * f0[1]
                    + (-6 * t2 + 6 * th) * b1 + (3 * t2 - 2 * th) * h * f1[1]
                )  # fmt: skip
                tn = th - g / dg if dg != 0.0 else 0.5 * (lo + hi)
                if not (lo < tn < hi):
                    tn = 0.5 * (lo + hi)
                if abs(tn - th) < 1e-15 or hi - lo < 1e-15:
                    th = tn
                    break
                th = tn
            tc = t + th * h
            if tc >= t_min:
                t2 = th * th
                t3 = t2 * th
                for i in range(4):
                    pts[npts, i] = (
                        (2 * t3 - 3 * t2 + 1) * y[i] + (t3 - 2 * t2 + th) * h * f0[i]
                        + (-2 * t3 + 3 * t2) * y1[i] + (t3 - t2) * h * f1[i]
                    )  # fmt: skip
                tp[npts] = tc
                npts += 1
        t += h
        for i in range(4):
            y[i] = y1[i]
            f0[i] = f1[i]
        n_acc += 1
        since_jac += 1
        enc = max(en, 1e-10)
        fac = SAFETY * enc ** (-PI_ALPHA / q) * err_prev ** (PI_BETA / q)
        fac = min(FAC_MAX, max(FAC_MIN, fac))
        if last_rej:
            fac = min(fac, 1.0)
        h *= fac
        err_prev = enc
        last_rej = False
    return n_acc, n_rej, n_jac, n_log, tp[:npts], pts[:npts]


rhs1 = peers.rhs1
jac1 = peers.jac1


# ----------------------------------------------------------- micro-benchmarks
@njit(cache=True)
def _loop_rhs1(y, p, out, n):
    acc = 0.0
    for k in range(n):
        y[1] = 1e-3 * (k % 7) - 2e-3
        rhs1(y, p, out)
        acc += out[1]
    return acc


@njit(cache=True)
def _loop_jac1(y, p, J, n):
    acc = 0.0
    for k in range(n):
        y[1] = 1e-3 * (k % 7) - 2e-3
        jac1(y, p, J)
        acc += J[1, 1]
    return acc


@njit(cache=True)
def _loop_lu(J, W, piv, n):
    acc = 0.0
    for k in range(n):
        sig = 10.0 + (k % 5)
        for i in range(4):
            for j in range(4):
                W[i, j] = -J[i, j]
            W[i, i] += sig
        lu4(W, piv)
        acc += W[3, 3]
    return acc


@njit(cache=True)
def _loop_solve(W, piv, b, n):
    acc = 0.0
    for k in range(n):
        b[0] = 1.0 + (k % 3)
        b[1] = 0.5
        b[2] = -0.25
        b[3] = 2.0
        lu4_solve(W, piv, b)
        acc += b[0]
    return acc


@njit(cache=True)
def _loop_control(err, y0, y1, rtol, atol, n):
    acc = 0.0
    err_prev = 0.5
    for k in range(n):
        err[0] = 1e-9 * (1 + k % 5)
        en = 0.0
        for i in range(4):
            sc = atol + rtol * max(abs(y0[i]), abs(y1[i]))
            en += (err[i] / sc) ** 2
        en = math.sqrt(en / 4)
        fac = SAFETY * max(en, 1e-10) ** (-PI_ALPHA / 5.0) * err_prev ** (PI_BETA / 5.0)
        acc += min(FAC_MAX, max(FAC_MIN, fac))
        err_prev = max(en, 1e-10)
    return acc


def _ns(fn, *args, n=200_000, reps=5):
    fn(*args, 10)  # compile
    best = math.inf
    for _ in range(reps):
        t0 = time.perf_counter()
        fn(*args, n)
        best = min(best, time.perf_counter() - t0)
    return best / n * 1e9


def _engine_pieces(p_engine, y, n):
    """ns per call of the engine's own compiled pieces, each timed if its current signature
    matches (the kernel is being rewritten: a piece that does not fit gets a note)."""
    import importlib

    from numba import njit as _nj

    from stickslip_fast.model import equations as model
    from stickslip_fast.model import linalg

    res = {}
    notes = []
    rhs_e, jb_e = model.rhs, model.jacobian_blocks
    wf, ws = linalg.w_factor, linalg.w_solve
    en_e = None
    for modname in ("stickslip_fast.core.problems", "stickslip_fast.core.steppers"):
        try:
            en_e = importlib.import_module(modname).error_norm
            break
        except (ImportError, AttributeError):
            continue

    @_nj
    def loop_rhs(y, p, out, n):
        acc = 0.0
        for k in range(n):
            y[1] = 1e-3 * (k % 7) - 2e-3
            rhs_e(y, p, 1, False, out)
            acc += out[1]
        return acc

    @_nj
    def loop_jac(y, p, jb, jcol, jrow, n):
        acc = 0.0
        for k in range(n):
            y[1] = 1e-3 * (k % 7) - 2e-3
            acc += jb_e(y, p, 1, False, jb, jcol, jrow)
            acc += jb[0, 1, 1]
        return acc

    @_nj
    def loop_factor(y, p, jb, jcol, jrow, lu, piv, z, n):
        jc = jb_e(y, p, 1, False, jb, jcol, jrow)
        acc = 0.0
        for k in range(n):
            acc += wf(10.0 + (k % 5), jb, jcol, jrow, jc, 1, False, lu, piv, z)
        return acc

    @_nj
    def loop_solve(y, p, jb, jcol, jrow, lu, piv, z, b, n):
        jc = jb_e(y, p, 1, False, jb, jcol, jrow)
        schur = wf(10.0, jb, jcol, jrow, jc, 1, False, lu, piv, z)
        acc = 0.0
        for k in range(n):
            b[0] = 1.0 + (k % 3)
            b[1] = 0.5
            b[2] = -0.25
            b[3] = 2.0
            ws(lu, piv, z, jrow, schur, 1, False, b)
            acc += b[0]
        return acc

    out = np.empty(4)
    jb = np.empty((1, 4, 4))
    jcol = np.zeros((1, 4))
    jrow = np.zeros((1, 4))
    lu = np.empty((1, 4, 4))
    piv = np.empty((1, 4), np.int64)
    z = np.zeros((1, 4))
    b = np.empty(4)
    jobs = [
        ("rhs", loop_rhs, (y.copy(), p_engine, out)),
        ("jacobian", loop_jac, (y.copy(), p_engine, jb, jcol, jrow)),
        ("factor", loop_factor, (y.copy(), p_engine, jb, jcol, jrow, lu, piv, z)),
        ("solve", loop_solve, (y.copy(), p_engine, jb, jcol, jrow, lu, piv, z, b)),
    ]
    if en_e is not None:

        @_nj
        def loop_norm(err, y0, y1, n):
            acc = 0.0
            for k in range(n):
                err[0] = 1e-9 * (1 + k % 5)
                acc += en_e(err, y0, y1, 1e-7, 1e-9)
            return acc

        jobs.append(("error_norm", loop_norm, (np.full(4, 1e-9), y.copy(), y.copy() + 1e-3)))
    for name, fn, args in jobs:
        try:
            res[name] = _ns(fn, *args, n=n)
        except Exception as exc:  # noqa: BLE001 - signature changed by the rewrite
            notes.append(f"{name}: {type(exc).__name__}")
    try:
        # one whole Rosenbrock attempt as the driver makes it: the small-N record, the
        # Jacobian at y0, then factor, 8 stages and the combination (steppers.rosenbrock_step)
        from stickslip_fast.core import problems as pr
        from stickslip_fast.core import steppers as sp

        M = sp.RODAS5P_METHOD
        G, RA, RC, RB, RE = M.gamma, M.a, M.C, M.b, M.b_err
        rb_step = sp.rosenbrock_step
        shape = pr.small_shape(1, False)

        @_nj
        def loop_step(y, p, n):
            prob = pr.make_small(pr.make_stickslip(p, 1, False, np.empty(p.size)), shape)
            lin = pr.alloc_bordered_linear(1, 4)
            f0 = np.empty(4)
            K = np.empty((RB.size, 4))
            ytmp = np.empty(4)
            ftmp = np.empty(4)
            y1 = np.empty(4)
            err = np.empty(4)
            pr.problem_f(prob, y, f0)
            pr.problem_jac(prob, y, lin)
            acc = 0.0
            for k in range(n):
                h = 1e-3 * (1 + k % 3)
                rb_step(G, RA, RC, RB, RE, prob, lin, y, f0, h, K, ytmp, ftmp, y1, err)
                acc += y1[0]
            return acc

        res["rosenbrock_step"] = _ns(loop_step, y.copy(), p_engine, n=max(n // 4, 10))
    except Exception as exc:  # noqa: BLE001
        notes.append(f"rosenbrock_step not timed: {type(exc).__name__}: {exc}")
    if notes:
        res["note"] = "; ".join(notes)
    return res


def transitions(log, n_log):
    """Split the attempts of a step log into near/away from stick<->slip switches."""
    L = log[:n_log]
    acc = L[:, 2] == 1.0
    ta = L[acc, 0]
    stick = np.abs(L[acc, 3]) < STICK_V
    sw = ta[1:][stick[1:] != stick[:-1]]  # switch times (start of the first step in the new regime)
    if len(sw) == 0:
        near = np.zeros(len(L), bool)
    else:
        t0 = L[:, 0]
        t1 = L[:, 0] + L[:, 1]
        j = np.searchsorted(sw, t0)
        d_next = np.where(j < len(sw), sw[np.minimum(j, len(sw) - 1)] - t1, np.inf)
        d_prev = np.where(j > 0, t0 - sw[np.maximum(j - 1, 0)], np.inf)
        near = (np.minimum(d_next, d_prev) <= NEAR) | ((j < len(sw)) & (d_next < 0))
    rej = L[:, 2] == 0.0
    return dict(
        n_switches=int(len(sw)),
        attempts=int(len(L)),
        attempts_near=int(near.sum()),
        rejected=int(rej.sum()),
        rejected_near=int((rej & near).sum()),
        time_near=float(min(len(sw) * 2 * NEAR, L[-1, 0] + L[-1, 1])) if len(L) else 0.0,
        sim_time=float(L[-1, 0] + L[-1, 1]) if len(L) else 0.0,
        stick_fraction_of_accepted=float(stick.mean()) if len(stick) else 0.0,
    )


def run(mode: str, log) -> dict:
    quick = mode == "quick"
    etas = [9.99] if quick else [2.0, 9.99]
    rtols = [1e-7] if quick else [1e-6, 1e-7, 1e-8, 1e-9]
    t_end, t_min = 1500.0, 1000.0
    n_micro = 20_000 if quick else 300_000
    peers.warm_up()
    out = dict(machine_note="one core, best of 5 for micro-benchmarks, best of 3 for runs")
    # ---- 2. ingredients
    p = peers.params(ssf.System.preset("asymmetric", eta=2.0).to_dict())
    y = np.array([0.1, -0.02, 0.05, 0.01])
    out4 = np.empty(4)
    J = np.empty((4, 4))
    W = np.empty((4, 4))
    piv = np.empty(4, np.int64)
    jac1(y, p, J)
    plain = dict(
        rhs=_ns(_loop_rhs1, y.copy(), p, out4, n=n_micro),
        jacobian=_ns(_loop_jac1, y.copy(), p, J, n=n_micro),
        factor=_ns(_loop_lu, J, W, piv, n=n_micro),
    )
    plain["solve"] = _ns(_loop_solve, W, piv, np.empty(4), n=n_micro)
    plain["error_norm+controller"] = _ns(
        _loop_control, np.full(4, 1e-9), y.copy(), y + 1e-3, 1e-7, 1e-9, n=n_micro
    )
    out["ingredients_ns_plain_4x4"] = plain
    try:
        if quick:
            raise RuntimeError("skipped in quick mode (compiles a dozen loops)")
        pe = ssf.System.preset("asymmetric", eta=2.0).to_array()
        out["ingredients_ns_engine"] = _engine_pieces(pe, y, n_micro)
    except Exception as exc:  # noqa: BLE001 - signatures change with the kernel rewrite
        out["ingredients_ns_engine"] = dict(note=f"engine pieces not timed: {exc!r}"[:300])
    s = 8

    def step_sum(d):
        if "rhs" not in d:
            return None
        ctrl = d.get("error_norm+controller", d.get("error_norm", 0.0))
        return s * d["rhs"] + d["jacobian"] + d["factor"] + s * d["solve"] + ctrl

    out["rodas5p_attempt_sum_ns"] = dict(
        plain=step_sum(plain), engine=step_sum(out["ingredients_ns_engine"])
    )
    # ---- 1 + 3. engine totals vs the replica variants
    tabs = dict(rodas5p=rodas5p(), ros34pw2=ros34pw2())
    variants = [
        ("replica rodas5p", "rodas5p", 1, False),
        ("replica rodas5p + order-aware rejection", "rodas5p", 1, True),
        ("replica ros34pw2", "ros34pw2", 1, False),
        ("replica ros34pw2, J every 3 steps", "ros34pw2", 3, False),
        ("replica ros34pw2, J every 10 steps", "ros34pw2", 10, False),
    ]
    if quick:
        variants = variants[:1]
    logbuf = np.empty((2_000_000, 4))
    cases = {}
    for eta in etas:
        system = ssf.System.preset("asymmetric", eta=eta)
        p = peers.params(system.to_dict())
        ref = trajectory_reference(eta, t_end, t_min, log=log)
        rows = []
        for rtol in rtols:
            atol = ATOL_FACTOR * rtol
            # engine
            best = math.inf
            for _ in range(3):
                t0 = time.perf_counter()
                r = ssf.simulate(system, t_end, t_min, rtol=rtol, atol=atol, max_points=10_000)
                best = min(best, time.perf_counter() - t0)
            from .peer_precision import point_error

            err, _ = point_error(ref["t"], ref["points"], r.t_poincare, r.poincare)
            att = r.n_steps + r.n_rejected
            row = dict(
                rtol=rtol,
                engine=dict(
                    time_ms=best * 1e3,
                    steps=int(r.n_steps),
                    rejected=int(r.n_rejected),
                    rejected_fraction=r.n_rejected / max(att, 1),
                    ns_per_attempt=best / max(att, 1) * 1e9,
                    error=err,
                ),  # fmt: skip
            )
            for name, tab, jev, pred in variants:
                g, A, C, M, E, q = tabs[tab]
                args = (g, A, C, M, E, q, p, t_end, t_min, rtol, atol, jev, pred, logbuf)
                rb_integrate(*args)
                best = math.inf
                for _ in range(3):
                    t0 = time.perf_counter()
                    na, nr, nj, nl, tp, pts = rb_integrate(*args)
                    best = min(best, time.perf_counter() - t0)
                err, _ = point_error(ref["t"], ref["points"], tp, pts)
                rec = dict(
                    time_ms=best * 1e3, steps=int(na), rejected=int(nr), jacobians=int(nj),
                    rejected_fraction=nr / max(na + nr, 1),
                    ns_per_attempt=best / max(na + nr, 1) * 1e9, error=err,
                )  # fmt: skip
                if name == "replica rodas5p":
                    rec["transitions"] = transitions(logbuf, nl)
                row[name] = rec
            rows.append(row)
            e = row["engine"]
            rp = row["replica rodas5p"]
            log(
                f"  profile eta={eta} rtol={rtol:g}: engine {e['time_ms']:.1f} ms "
                f"{e['steps']}+{e['rejected']} ({e['ns_per_attempt']:.0f} ns/attempt, err "
                f"{e['error']:.1e}); replica {rp['time_ms']:.1f} ms {rp['steps']}+{rp['rejected']}"
                f" ({rp['ns_per_attempt']:.0f} ns, err {rp['error']:.1e})"
            )
        cases[f"asymmetric_eta{eta}"] = rows
    out["cases"] = cases
    out["stick_v"] = STICK_V
    out["near"] = NEAR
    out["loadavg_at_end"] = list(os.getloadavg())
    return out


# ------------------------------------------------- Jacobian share at large N (W-method bound)
def jacobian_share(n_list=(1, 8, 64, 512), n_calls=2000) -> dict:
    """ns per call of the generic kernel's pieces for N disks on a DC motor, and the share
    of one Rodas5P attempt (7 RHS, 1 Jacobian, 1 factor, 8 solves) that the Jacobian and
    the factorisation take: the most that reusing them (a W-method) could save per attempt.

    ``python3 -c "from benchmarks.profile_kernel import jacobian_share as j; print(j())"``
    """
    from numba import njit as _nj

    from stickslip_fast.model import equations as model
    from stickslip_fast.model import linalg
    from stickslip_fast.model.params import P_ETA, P_ETAP, eta_prime

    rhs_e, jb_e, wf, ws = model.rhs, model.jacobian_blocks, linalg.w_factor, linalg.w_solve

    @_nj
    def loop_rhs(y, p, n_osc, out, n):
        acc = 0.0
        for k in range(n):
            y[1] = 1e-3 * (k % 7) - 2e-3
            rhs_e(y, p, n_osc, True, out)
            acc += out[1]
        return acc

    @_nj
    def loop_jac(y, p, n_osc, jb, jcol, jrow, n):
        acc = 0.0
        for k in range(n):
            y[1] = 1e-3 * (k % 7) - 2e-3
            acc += jb_e(y, p, n_osc, True, jb, jcol, jrow)
        return acc

    @_nj
    def loop_factor(y, p, n_osc, jb, jcol, jrow, lu, piv, z, n):
        jc = jb_e(y, p, n_osc, True, jb, jcol, jrow)
        acc = 0.0
        for k in range(n):
            acc += wf(10.0 + (k % 5), jb, jcol, jrow, jc, n_osc, True, lu, piv, z)
        return acc

    @_nj
    def loop_solve(y, p, n_osc, jb, jcol, jrow, lu, piv, z, b, n):
        jc = jb_e(y, p, n_osc, True, jb, jcol, jrow)
        schur = wf(10.0, jb, jcol, jrow, jc, n_osc, True, lu, piv, z)
        acc = 0.0
        for k in range(n):
            b[0] = 1.0 + (k % 3)
            ws(lu, piv, z, jrow, schur, n_osc, True, b)
            acc += b[0]
        return acc

    out = {}
    for n_osc in n_list:
        s = ssf.System.preset("asymmetric", drive="dc-motor", n_oscillators=n_osc)
        p = s.to_array()
        p[P_ETAP] = eta_prime(p[P_ETA])
        n = s.n_state
        rng = np.random.default_rng(0)
        y = 0.01 * rng.standard_normal(n)
        jb, jcol, jrow = np.zeros((n_osc, 4, 4)), np.zeros((n_osc, 4)), np.zeros((n_osc, 4))
        lu, piv = np.zeros((n_osc, 4, 4)), np.zeros((n_osc, 4), np.int64)
        z = np.zeros((n_osc, 4))
        calls = max(10, n_calls // n_osc)
        t = dict(
            rhs=_ns(loop_rhs, y.copy(), p, n_osc, np.empty(n), n=calls),
            jacobian=_ns(loop_jac, y.copy(), p, n_osc, jb, jcol, jrow, n=calls),
            factor=_ns(loop_factor, y.copy(), p, n_osc, jb, jcol, jrow, lu, piv, z, n=calls),
            solve=_ns(
                loop_solve, y.copy(), p, n_osc, jb, jcol, jrow, lu, piv, z, np.ones(n), n=calls
            ),  # fmt: skip
        )
        attempt = 7 * t["rhs"] + t["jacobian"] + t["factor"] + 8 * t["solve"]
        out[n_osc] = dict(
            ns=t, attempt_ns=attempt,
            jacobian_and_factor_share=(t["jacobian"] + t["factor"]) / attempt,
        )  # fmt: skip
    return out
