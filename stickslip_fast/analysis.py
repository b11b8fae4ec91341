"""Analysis of trajectories: largest Lyapunov exponent and synchronization measures.

Largest Lyapunov exponent
-------------------------
:func:`largest_lyapunov` integrates the state ``y`` together with one tangent
vector ``u`` of the variational equations, ``u' = J(y) u``, as one autonomous
system ``Y = (y, u)`` with the compiled Rosenbrock method Rodas5P (the friction
law is stiff while a disk sticks). The exact Jacobian of the augmented system is

    [[J(y),  0   ],
     [H(y,u), J(y)]],      H(y, u) v = D^2 f(y)[u, v],

so W = sigma I - J_aug is block lower triangular, [[W, 0], [-H, W]]: each stage
costs two O(N) solves with the *same* factored W (:func:`linalg.w_factor`) plus
the bilinear form D^2 f(y)[u, v], which only involves the second derivatives of
the friction law (:func:`model.friction_second_partials`). The tangent vector
is renormalised every ``renorm_dt`` (Benettin et al.); the exponent is the mean
logarithmic growth rate after ``t_transient``.

Synchronization
---------------
:func:`phases_from_events` gives each disk a phase from its own Poincare events
(local minima of x_i), the phase differences relative to disk 1, a classification
("in-phase", "anti-phase", "desynchronized") and the Kuramoto order parameter.
:func:`sync_error` is a cheap sweep-level measure from the Poincare points alone.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
from numba import njit

from .integrators import initial_step
from .linalg import w_factor, w_solve
from .model import eta_prime, friction_partials, friction_second_partials, jacobian_blocks
from .poincare import ST_MAX_STEPS, ST_NONFINITE, ST_OK, ST_UNDERFLOW, STATUS_NAMES
from .system import (
    P_BETA,
    P_C,
    P_C12,
    P_EPS,
    P_ETA,
    P_ETAP,
    P_K12,
    P_M,
    P_MU,
    P_TB,
    P_VB,
    P_VB0,
    System,
)
from .tableaus import RODAS5P

__all__ = [
    "LyapunovResult",
    "largest_lyapunov",
    "tangent_rhs",
    "second_derivative_form",
    "SyncResult",
    "event_times",
    "phases_from_events",
    "sync_error",
    "wrap_phase",
]

_JIT = dict(cache=True, nogil=True)

_RB_GAMMA = float(RODAS5P.gamma)
_RB_A = RODAS5P.a
_RB_C = RODAS5P.C
_RB_B = RODAS5P.b
_RB_E = RODAS5P.b_err
_RB_Q = RODAS5P.embedded_order + 1.0

# step-size control, as in trajectory.integrate
_SAFETY = 0.9
_FAC_MIN = 0.2
_FAC_MAX = 6.0
_PI_ALPHA = 0.7
_PI_BETA = 0.4
# renormalise early (without recording) when |u| leaves [1/_BIG, _BIG]
_BIG = 1e100

DEFAULT_LYAP_RTOL = 1e-8
DEFAULT_LYAP_ATOL = 1e-10


# --------------------------------------------------------------------------- model
@njit(**_JIT)
def tangent_rhs(
    y: np.ndarray,
    u: np.ndarray,
    p: np.ndarray,
    n_osc: int,
    dc: bool,
    dydt: np.ndarray,
    dudt: np.ndarray,
) -> None:
    """Write f(y) into ``dydt`` and J(y) u into ``dudt`` (one friction evaluation).

    Same equations as :func:`stickslip_fast.model.rhs`; J(y) u is the directional
    derivative of f, built from :func:`model.friction_partials`.
    """
    m = p[P_M]
    k12 = p[P_K12]
    c = p[P_C]
    c12 = p[P_C12]
    mu = p[P_MU]
    eps = p[P_EPS]
    etap = p[P_ETAP]
    inv_m = 1.0 / m
    vb = y[4 * n_osc] if dc else p[P_VB]
    uvb = u[4 * n_osc] if dc else 0.0
    t_sum = 0.0
    dt_sum = 0.0
    for i in range(n_osc):
        j = 4 * i
        x = y[j]
        dx = y[j + 1]
        ph = y[j + 2]
        dph = y[j + 3]
        t, mm, t_v, t_w, m_v, m_w = friction_partials(dx - vb, dph, eps, etap)
        dsv = u[j + 1] - uvb
        dw = u[j + 3]
        dt = t_v * dsv + t_w * dw
        dm = m_v * dsv + m_w * dw
        t_sum += t
        dt_sum += dt
        dydt[j] = dx
        dydt[j + 1] = -(c * dx + c12 * dph) - (x + k12 * ph) - mu * t
        dydt[j + 2] = dph
        dydt[j + 3] = (-(c12 * dx + c * dph) - (k12 * x + ph) - mu * mm) * inv_m
        dudt[j] = u[j + 1]
        dudt[j + 1] = -(c * u[j + 1] + c12 * u[j + 3]) - (u[j] + k12 * u[j + 2]) - mu * dt
        dudt[j + 2] = u[j + 3]
        dudt[j + 3] = (-(c12 * u[j + 1] + c * u[j + 3]) - (k12 * u[j] + u[j + 2]) - mu * dm) * inv_m
    if dc:
        inv_tb = 1.0 / p[P_TB]
        bn = p[P_BETA] / n_osc
        dydt[4 * n_osc] = (p[P_VB0] - vb + bn * t_sum) * inv_tb
        dudt[4 * n_osc] = (-uvb + bn * dt_sum) * inv_tb


@njit(**_JIT)
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
    so only the dx, dphi (and v_b) rows are nonzero.
    """
    mu = p[P_MU]
    eps = p[P_EPS]
    etap = p[P_ETAP]
    inv_m = 1.0 / p[P_M]
    vb = y[4 * n_osc] if dc else p[P_VB]
    uvb = u[4 * n_osc] if dc else 0.0
    vvb = v[4 * n_osc] if dc else 0.0
    acc = 0.0
    for i in range(n_osc):
        j = 4 * i
        t_vv, t_vw, t_ww, m_vv, m_vw, m_ww = friction_second_partials(
            y[j + 1] - vb, y[j + 3], eps, etap
        )
        a1 = u[j + 1] - uvb
        b1 = u[j + 3]
        a2 = v[j + 1] - vvb
        b2 = v[j + 3]
        cross = a1 * b2 + b1 * a2
        d2t = t_vv * a1 * a2 + t_vw * cross + t_ww * b1 * b2
        d2m = m_vv * a1 * a2 + m_vw * cross + m_ww * b1 * b2
        out[j] = 0.0
        out[j + 1] = -mu * d2t
        out[j + 2] = 0.0
        out[j + 3] = -mu * d2m * inv_m
        acc += d2t
    if dc:
        out[4 * n_osc] = p[P_BETA] / n_osc * acc / p[P_TB]


# -------------------------------------------------------------------------- kernel
@njit(**_JIT)
def _tangent_rosenbrock_step(
    y0, u0, fy0, fu0, h, p, n_osc, dc, jb, jcol, jrow, jcorner, lu, piv, z,
    Ky, Ku, ytmp, utmp, fy, fu, hv, y1, u1, ey, eu,
):  # fmt: skip
    """One Rodas5P step of the augmented system (y, u), u' = J(y) u.

    Same transformed formulation as :func:`integrators.rosenbrock_step`; the
    augmented W = [[W, 0], [-H, W]] is solved by block forward substitution:
    W k_y = r_y, then W k_u = r_u + H(y0, u0) k_y. Returns False if W is
    singular or a stage is not finite.
    """
    s = _RB_B.size
    n = y0.size
    schur = w_factor(1.0 / (h * _RB_GAMMA), jb, jcol, jrow, jcorner, n_osc, dc, lu, piv, z)
    if not math.isfinite(schur):
        return False
    inv_h = 1.0 / h
    for st in range(s):
        if st == 0:
            for i in range(n):
                fy[i] = fy0[i]
                fu[i] = fu0[i]
        else:
            for i in range(n):
                ay = 0.0
                au = 0.0
                for j in range(st):
                    ay += _RB_A[st, j] * Ky[j, i]
                    au += _RB_A[st, j] * Ku[j, i]
                ytmp[i] = y0[i] + ay
                utmp[i] = u0[i] + au
            tangent_rhs(ytmp, utmp, p, n_osc, dc, fy, fu)
        ky = Ky[st]
        ku = Ku[st]
        for i in range(n):
            ay = 0.0
            au = 0.0
            for j in range(st):
                ay += _RB_C[st, j] * Ky[j, i]
                au += _RB_C[st, j] * Ku[j, i]
            ky[i] = fy[i] + inv_h * ay
            ku[i] = fu[i] + inv_h * au
        w_solve(lu, piv, z, jrow, schur, n_osc, dc, ky)
        second_derivative_form(y0, u0, ky, p, n_osc, dc, hv)
        for i in range(n):
            ku[i] += hv[i]
        w_solve(lu, piv, z, jrow, schur, n_osc, dc, ku)
        for i in range(n):
            if not (math.isfinite(ky[i]) and math.isfinite(ku[i])):
                return False
    for i in range(n):
        ay = 0.0
        au = 0.0
        ea = 0.0
        eb = 0.0
        for j in range(s):
            ay += _RB_B[j] * Ky[j, i]
            au += _RB_B[j] * Ku[j, i]
            ea += _RB_E[j] * Ky[j, i]
            eb += _RB_E[j] * Ku[j, i]
        y1[i] = y0[i] + ay
        u1[i] = u0[i] + au
        ey[i] = ea
        eu[i] = eb
    return True


@njit(**_JIT)
def _norm(u: np.ndarray) -> float:
    acc = 0.0
    for i in range(u.size):
        acc += u[i] * u[i]
    return math.sqrt(acc)


@njit(**_JIT)
def lyapunov_kernel(
    y0: np.ndarray,
    u0: np.ndarray,
    p: np.ndarray,
    n_osc: int,
    dc: bool,
    t_end: float,
    t_transient: float,
    rtol: float,
    atol: float,
    tangent_atol: float,
    renorm_dt: float,
    max_steps: int,
    conv_t: np.ndarray,
    conv_est: np.ndarray,
    y_end: np.ndarray,
    stats: np.ndarray,
    fstats: np.ndarray,
) -> int:
    """Benettin's algorithm for the largest Lyapunov exponent; returns a status code.

    Integrates (y, u) from t = 0 to ``t_end`` with adaptive Rodas5P. The error
    norm is the RMS over both parts, y scaled by atol + rtol |y| and u by
    tangent_atol |u_0| + rtol |u| (u is a direction: its absolute tolerance is
    relative to its current length). The tangent vector is renormalised at the
    first step end at or after t_transient (where the averaging starts), then at
    step ends at least ``renorm_dt`` apart, recording (t, running estimate) into
    ``conv_t``/``conv_est``. Outputs: ``stats`` = (steps, rejected, records),
    ``fstats`` = (exponent, t_start, t_final, log-growth sum), ``y_end``.
    """
    n = y0.size
    p = p.copy()
    p[P_ETAP] = eta_prime(p[P_ETA])
    y = y0.copy()
    u = u0.copy()
    ynew = np.empty(n)
    unew = np.empty(n)
    ytmp = np.empty(n)
    utmp = np.empty(n)
    fy = np.empty(n)
    fu = np.empty(n)
    fy0 = np.empty(n)
    fu0 = np.empty(n)
    hv = np.empty(n)
    ey = np.empty(n)
    eu = np.empty(n)
    stages = _RB_B.size
    Ky = np.empty((stages, n))
    Ku = np.empty((stages, n))
    jb = np.empty((n_osc, 4, 4))
    jcol = np.zeros((n_osc, 4))
    jrow = np.zeros((n_osc, 4))
    lu = np.empty((n_osc, 4, 4))
    piv = np.empty((n_osc, 4), dtype=np.int64)
    z = np.zeros((n_osc, 4))

    un = _norm(u)
    for i in range(n):
        u[i] /= un
    tangent_rhs(y, u, p, n_osc, dc, fy0, fu0)
    h = initial_step(y, fy0, p, n_osc, dc, rtol, atol, _RB_Q - 1.0, ytmp, fy)
    h = min(h, t_end)

    status = ST_OK
    t = 0.0
    n_steps = 0
    n_rej = 0
    n_rec = 0
    cap = conv_t.shape[0]
    log_sum = 0.0
    started = False
    t_start = t_transient
    next_renorm = t_transient
    err_prev = 1.0
    last_rejected = False
    jac_fresh = False
    jcorner = 0.0
    inv_2n = 1.0 / (2.0 * n)

    if t_transient <= 0.0:
        started = True
        t_start = 0.0
        next_renorm = renorm_dt

    while t < t_end:
        if n_steps >= max_steps:
            status = ST_MAX_STEPS
            break
        if t + h >= t_end or t + 1.01 * h >= t_end:
            h = t_end - t
        if not jac_fresh:
            jcorner = jacobian_blocks(y, p, n_osc, dc, jb, jcol, jrow)
            jac_fresh = True
        ok = _tangent_rosenbrock_step(
            y, u, fy0, fu0, h, p, n_osc, dc, jb, jcol, jrow, jcorner, lu, piv, z,
            Ky, Ku, ytmp, utmp, fy, fu, hv, ynew, unew, ey, eu,
        )  # fmt: skip
        en = 0.0
        if ok:
            un = _norm(u)
            acc = 0.0
            for i in range(n):
                sc = atol + rtol * max(abs(y[i]), abs(ynew[i]))
                e = ey[i] / sc
                acc += e * e
                sc = tangent_atol * un + rtol * max(abs(u[i]), abs(unew[i]))
                e = eu[i] / sc
                acc += e * e
            en = math.sqrt(acc * inv_2n)
            if not math.isfinite(en):
                ok = False
        if not ok or en > 1.0:
            n_rej += 1
            if ok:
                fac = max(_FAC_MIN, _SAFETY * en ** (-1.0 / _RB_Q))
            else:
                fac = 0.25
            h *= fac
            last_rejected = True
            if h < 1e-14 * max(1.0, abs(t)):
                status = ST_UNDERFLOW if ok else ST_NONFINITE
                break
            continue

        # accepted
        n_steps += 1
        t = t + h
        for i in range(n):
            y[i] = ynew[i]
            u[i] = unew[i]
        un = _norm(u)
        if not (math.isfinite(un) and un > 0.0):
            status = ST_NONFINITE
            break
        if not started:
            # before the averaging window only the direction of u matters
            for i in range(n):
                u[i] /= un
            if t >= t_transient:
                started = True
                t_start = t
                next_renorm = t + renorm_dt
        elif t >= next_renorm or t >= t_end:
            log_sum += math.log(un)
            for i in range(n):
                u[i] /= un
            next_renorm = t + renorm_dt
            if n_rec < cap:
                conv_t[n_rec] = t
                conv_est[n_rec] = log_sum / (t - t_start)
                n_rec += 1
        elif un > _BIG or un < 1.0 / _BIG:
            log_sum += math.log(un)
            for i in range(n):
                u[i] /= un
        tangent_rhs(y, u, p, n_osc, dc, fy0, fu0)
        jac_fresh = False
        en = max(en, 1e-10)
        fac = _SAFETY * en ** (-_PI_ALPHA / _RB_Q) * err_prev ** (_PI_BETA / _RB_Q)
        fac = min(_FAC_MAX, max(_FAC_MIN, fac))
        if last_rejected:
            fac = min(fac, 1.0)
        h *= fac
        err_prev = en
        last_rejected = False

    for i in range(n):
        y_end[i] = y[i]
    stats[0] = n_steps
    stats[1] = n_rej
    stats[2] = n_rec
    fstats[1] = t_start
    fstats[2] = t
    fstats[3] = log_sum
    if started and t > t_start:
        fstats[0] = log_sum / (t - t_start)
    else:
        fstats[0] = math.nan
    return status


# ----------------------------------------------------------------------- public API
@dataclass
class LyapunovResult:
    """What :func:`largest_lyapunov` returns.

    Attributes
    ----------
    exponent : float
        Largest Lyapunov exponent (Benettin): log(|u(t_final)| / |u(t_start)|)
        / (t_final - t_start), NaN if the run failed before t_transient.
    exponent_fit : float
        Least-squares slope of the cumulative log growth L(t) over the
        convergence records. Same limit; for a periodic orbit the bounded
        periodic part of L biases it only by O(1 / T^2) instead of O(1 / T).
    convergence : ndarray, shape (k, 2)
        Columns (t, running estimate) at each renormalisation after t_transient.
    status : str
        "ok", "nonfinite", "step-underflow" or "max-steps".
    t_start, t_final : float
        Averaging window (t_start is the first step end at or after t_transient).
    n_steps, n_rejected : int
        Accepted and rejected steps of the augmented system.
    final_state : ndarray
        State y at t_final.
    runtime : float
        Wall-clock seconds of the compiled kernel.
    settings : dict
    """

    exponent: float
    exponent_fit: float
    convergence: np.ndarray
    status: str
    t_start: float
    t_final: float
    n_steps: int
    n_rejected: int
    final_state: np.ndarray
    runtime: float
    settings: dict = field(default_factory=dict)

    def __repr__(self) -> str:
        return (
            f"LyapunovResult(exponent={self.exponent:.6g}, exponent_fit={self.exponent_fit:.6g}, "
            f"status={self.status!r}, "
            f"n_steps={self.n_steps}, runtime={self.runtime:.3g}s)"
        )


def largest_lyapunov(
    system: System,
    t_end: float,
    t_transient: float = 0.0,
    y0: np.ndarray | list | None = None,
    rtol: float = DEFAULT_LYAP_RTOL,
    atol: float = DEFAULT_LYAP_ATOL,
    renorm_dt: float = 1.0,
    *,
    u0: np.ndarray | list | None = None,
    tangent_atol: float = 1e-8,
    max_steps: int = 50_000_000,
) -> LyapunovResult:
    """Largest Lyapunov exponent from the variational equations (Benettin).

    Integrates y' = f(y) and u' = J(y) u with the analytic Jacobian, using a
    compiled Rodas5P kernel on the augmented autonomous system, and averages
    the log growth of |u| over [t_transient, t_end].

    Parameters
    ----------
    system : System
    t_end : float
        Final time.
    t_transient : float
        Averaging starts at the first step end at or after this time; before it
        only the direction of u evolves.
    y0 : array_like, optional
        Initial state (default zeros, as in :func:`stickslip_fast.simulate`).
    rtol, atol : float
        Tolerances of the y part (defaults 1e-8 and 1e-10, as ``simulate``).
    renorm_dt : float
        Minimum time between renormalisations (and convergence records).
    u0 : array_like, optional
        Initial tangent vector; default a fixed pseudo-random unit vector
        (seed 12345), which has components along every direction.
    tangent_atol : float
        Absolute tolerance of the tangent part relative to |u| (default 1e-8:
        on the presets the exponent agrees with 1e-10 to ~1e-6 at a third fewer
        steps).
    max_steps : int
        Give up with status "max-steps" after this many accepted steps.

    Returns
    -------
    LyapunovResult

    Notes
    -----
    For a periodic orbit of an autonomous system the largest exponent is 0
    (the flow direction neither grows nor shrinks on average); the finite-time
    estimate carries a bias of order log(|f(y_end)| / |f(y_start)|) / (t_end -
    t_start), which decays like 1 / t_end.

    Examples
    --------
    >>> from stickslip_fast import System
    >>> res = largest_lyapunov(System.preset("symmetric", eta=5.0), 6000, 1000)
    >>> abs(res.exponent) < 1e-3  # doctest: +SKIP
    True
    """
    import time

    if not isinstance(system, System):
        raise TypeError(f"system must be a stickslip_fast.System, got {type(system).__name__}")
    for name, value in (("t_end", t_end), ("rtol", rtol), ("atol", atol), ("renorm_dt", renorm_dt)):
        if not (math.isfinite(value) and value > 0):
            raise ValueError(f"{name} must be finite and > 0, got {value!r}")
    if not (math.isfinite(t_transient) and 0 <= t_transient < t_end):
        raise ValueError(f"t_transient must be in [0, t_end), got {t_transient!r}")
    tangent_atol = float(tangent_atol)
    if not (math.isfinite(tangent_atol) and tangent_atol > 0):
        raise ValueError(f"tangent_atol must be finite and > 0, got {tangent_atol!r}")
    y_init = system.initial_state(y0)
    n = system.n_state
    if u0 is None:
        u_init = np.random.default_rng(12345).standard_normal(n)
    else:
        u_init = np.asarray(u0, dtype=float)
        if u_init.shape != (n,) or not np.all(np.isfinite(u_init)) or not np.any(u_init):
            raise ValueError(f"u0 must be a finite nonzero vector of length {n}")
    cap = int((t_end - t_transient) / renorm_dt) + 2
    conv_t = np.empty(cap)
    conv_est = np.empty(cap)
    y_end = np.empty(n)
    stats = np.zeros(3, dtype=np.int64)
    fstats = np.zeros(4)
    t0 = time.perf_counter()
    code = lyapunov_kernel(
        y_init, u_init, system.to_array(), system.n_oscillators, system.is_dc_motor,
        float(t_end), float(t_transient), float(rtol), float(atol), tangent_atol,
        float(renorm_dt), int(max_steps), conv_t, conv_est, y_end, stats, fstats,
    )  # fmt: skip
    runtime = time.perf_counter() - t0
    k = int(stats[2])
    conv = np.column_stack([conv_t[:k], conv_est[:k]])
    t_start = float(fstats[1])
    if k >= 2:
        tt = np.concatenate([[t_start], conv[:, 0]])
        growth = np.concatenate([[0.0], conv[:, 1] * (conv[:, 0] - t_start)])
        slope = float(np.polyfit(tt, growth, 1)[0])
    else:
        slope = math.nan
    return LyapunovResult(
        exponent=float(fstats[0]),
        exponent_fit=slope,
        convergence=conv,
        status=STATUS_NAMES[code],
        t_start=t_start,
        t_final=float(fstats[2]),
        n_steps=int(stats[0]),
        n_rejected=int(stats[1]),
        final_state=y_end,
        runtime=runtime,
        settings=dict(
            t_end=float(t_end),
            t_transient=float(t_transient),
            rtol=float(rtol),
            atol=float(atol),
            tangent_atol=tangent_atol,
            renorm_dt=float(renorm_dt),
            max_steps=int(max_steps),
        ),
    )


# ------------------------------------------------------------------ synchronization
def wrap_phase(a: np.ndarray | float) -> np.ndarray:
    """Wrap angles to (-pi, pi]."""
    a = np.asarray(a, dtype=float)
    w = np.mod(a + np.pi, 2.0 * np.pi) - np.pi
    return np.where(w == -np.pi, np.pi, w)


def event_times(t: np.ndarray, dx: np.ndarray) -> np.ndarray:
    """Times of the upward zero crossings of ``dx`` (local minima of x).

    Linear interpolation between the samples ``dx[k] < 0 <= dx[k + 1]``.

    Parameters
    ----------
    t : ndarray, shape (n,)
        Increasing sample times.
    dx : ndarray, shape (n,)
        Velocity samples.

    Returns
    -------
    ndarray
        Crossing times in increasing order.
    """
    t = np.asarray(t, dtype=float)
    dx = np.asarray(dx, dtype=float)
    if t.shape != dx.shape or t.ndim != 1:
        raise ValueError("t and dx must be 1-D arrays of the same length")
    k = np.nonzero((dx[:-1] < 0.0) & (dx[1:] >= 0.0))[0]
    d0 = dx[k]
    d1 = dx[k + 1]
    frac = d0 / (d0 - d1)
    return t[k] + frac * (t[k + 1] - t[k])


def _phase_at(times: np.ndarray, events: np.ndarray) -> np.ndarray:
    """theta(t) = 2 pi (k + (t - t_k) / (t_{k+1} - t_k)); NaN outside the events."""
    out = np.full(times.shape, np.nan)
    if events.size < 2:
        return out
    k = np.searchsorted(events, times, side="right") - 1
    inside = (k >= 0) & (k < events.size - 1)
    kk = k[inside]
    out[inside] = 2.0 * np.pi * (kk + (times[inside] - events[kk]) / (events[kk + 1] - events[kk]))
    return out


@dataclass
class SyncResult:
    """What :func:`phases_from_events` returns.

    Attributes
    ----------
    events : list of ndarray
        Event times (local minima of x_i) of every oscillator.
    t : ndarray
        Sample times where every phase is defined.
    theta : ndarray, shape (N, len(t))
        Unwrapped phases on ``t``.
    t_ref : ndarray
        Oscillator 1's events at which the differences are taken.
    phase_diff : ndarray, shape (N, len(t_ref))
        theta_i - theta_1 at oscillator 1's events, wrapped to (-pi, pi]
        (row 0 is zero).
    mean_diff : ndarray, shape (N,)
        Circular mean of each row of ``phase_diff``.
    spread : ndarray, shape (N,)
        Largest |wrap(phase_diff - mean_diff)| of each row (drift / locking test).
    labels : list of str
        Per oscillator (index 0 is oscillator 1, "reference").
    classification : str
        "in-phase" or "anti-phase" if every other oscillator is, else
        "desynchronized" (also for mixed labels with N > 2: "mixed").
    order_parameter : float
        Kuramoto R = time average of |mean_i exp(i theta_i)| over ``t``.
    """

    events: list
    t: np.ndarray
    theta: np.ndarray
    t_ref: np.ndarray
    phase_diff: np.ndarray
    mean_diff: np.ndarray
    spread: np.ndarray
    labels: list
    classification: str
    order_parameter: float


def phases_from_events(
    t: np.ndarray,
    y: np.ndarray,
    n_oscillators: int,
    tol: float = 0.3,
) -> SyncResult:
    """Phases of the oscillators from their own Poincare events; phase locking.

    Each oscillator i gets events at the local minima of x_i (upward zero
    crossings of dx_i, linearly interpolated on the samples; use a small
    ``sample_dt`` in :func:`stickslip_fast.simulate`) and the phase
    theta_i(t) = 2 pi (k + (t - t_k) / (t_{k+1} - t_k)) between events k, k+1.

    Parameters
    ----------
    t : ndarray, shape (n,)
        Uniform or increasing sample times.
    y : ndarray, shape (n, n_state)
        Samples in engine layout [x1, dx1, phi1, dphi1, x2, ..., (vb)].
    n_oscillators : int
        Number of disks N.
    tol : float
        Tolerance in radians: "in-phase" if |mean diff| < tol, "anti-phase" if
        |mean diff - pi| < tol, in both cases only if the differences stay
        within ``tol`` of their mean (locked); otherwise "desynchronized".

    Returns
    -------
    SyncResult

    Examples
    --------
    >>> t = np.linspace(0, 100, 20001)
    >>> y = np.column_stack([-np.cos(t), np.sin(t), 0 * t, 0 * t] * 2)
    >>> phases_from_events(t, y, 2).classification
    'in-phase'
    """
    t = np.asarray(t, dtype=float)
    y = np.asarray(y, dtype=float)
    if y.ndim != 2 or y.shape[0] != t.size or y.shape[1] < 4 * n_oscillators:
        raise ValueError("y must have shape (len(t), n_state >= 4 N)")
    if n_oscillators < 1:
        raise ValueError("n_oscillators must be >= 1")
    events = [event_times(t, y[:, 4 * i + 1]) for i in range(n_oscillators)]
    if any(ev.size < 2 for ev in events):
        raise ValueError("every oscillator needs at least two events (local minima of x_i)")
    lo = max(ev[0] for ev in events)
    hi = min(ev[-1] for ev in events)
    mask = (t >= lo) & (t < hi)
    tt = t[mask]
    theta = np.array([_phase_at(tt, ev) for ev in events])
    t_ref = events[0][(events[0] >= lo) & (events[0] < hi)]
    diff = np.zeros((n_oscillators, t_ref.size))
    th1 = _phase_at(t_ref, events[0])
    for i in range(1, n_oscillators):
        diff[i] = wrap_phase(_phase_at(t_ref, events[i]) - th1)
    if t_ref.size:
        mean = np.angle(np.mean(np.exp(1j * diff), axis=1))
        spread = np.max(np.abs(wrap_phase(diff - mean[:, None])), axis=1)
    else:
        mean = np.full(n_oscillators, np.nan)
        spread = np.full(n_oscillators, np.nan)
    labels = ["reference"]
    for i in range(1, n_oscillators):
        if not (spread[i] < tol):
            labels.append("desynchronized")
        elif abs(mean[i]) < tol:
            labels.append("in-phase")
        elif abs(wrap_phase(mean[i] - np.pi)) < tol:
            labels.append("anti-phase")
        else:
            labels.append("desynchronized")
    others = set(labels[1:])
    if not others:
        classification = "in-phase"
    elif len(others) == 1:
        classification = labels[1]
    else:
        classification = "mixed"
    if tt.size:
        order = float(np.mean(np.abs(np.mean(np.exp(1j * theta), axis=0))))
    else:
        order = math.nan
    return SyncResult(
        events=events,
        t=tt,
        theta=theta,
        t_ref=t_ref,
        phase_diff=diff,
        mean_diff=mean,
        spread=spread,
        labels=labels,
        classification=classification,
        order_parameter=order,
    )


def sync_error(points: np.ndarray, n_oscillators: int) -> float:
    """Mean distance between disk i's and disk 1's states at the Poincare points.

    For each point (the full state at a local minimum of x_1) and each disk
    i >= 2, the Euclidean distance between (x_i, dx_i, phi_i, dphi_i) and
    (x_1, dx_1, phi_1, dphi_1); averaged over points and disks. Zero when all
    disks move identically (in phase); cheap enough for every value of a sweep.

    Parameters
    ----------
    points : ndarray, shape (k, n_state)
        Poincare points in engine layout (NaN rows, e.g. sweep padding, are
        ignored).
    n_oscillators : int

    Returns
    -------
    float
        0.0 for N = 1; NaN if there are no finite points.
    """
    pts = np.asarray(points, dtype=float)
    if pts.ndim != 2 or pts.shape[1] < 4 * n_oscillators:
        raise ValueError("points must have shape (k, n_state >= 4 N)")
    if n_oscillators == 1:
        return 0.0
    pts = pts[np.all(np.isfinite(pts[:, : 4 * n_oscillators]), axis=1)]
    if pts.shape[0] == 0:
        return math.nan
    ref = pts[:, 0:4]
    d = [np.linalg.norm(pts[:, 4 * i : 4 * i + 4] - ref, axis=1) for i in range(1, n_oscillators)]
    return float(np.mean(d))
