"""Peer solvers, each in its best compiled form, on the single-disk constant-belt problem.

Every peer integrates the same problem (one disk, constant belt, 4 states) from rest and
returns the Poincare points (upward zero crossings of dx1, t >= t_min). What a user of
each library would write in ten minutes, and no handicap:

* the RHS and analytic Jacobian are ``@njit`` functions of this module (written from the
  paper's equations like tests/reference/scipy_model.py; nothing from stickslip_fast),
  so every peer gets the same compiled right-hand side;
* crossings come either from the solver's own root finding (SciPy events, CVODE
  rootfinding) or from :func:`grid_crossings`, an ``@njit`` finder that refines each
  sign change of dx1 on an output grid on the cubic Hermite interpolant (slopes from
  the RHS) by safeguarded Newton: about 1 us per crossing, against the solver's
  milliseconds.

``integrate_only=True`` variants run the same solver without any output grid or
event function, to separate the integration from the Poincare detection.
"""

from __future__ import annotations

import math
import sys
import time
from pathlib import Path

import numpy as np
from numba import njit, prange

ROOT = Path(__file__).resolve().parents[1]

MXSTEP = 100_000_000
GRID_DT = 0.01  # output grid of the grid-based peers (cubic Hermite error ~ dt^4/384 |y''''|)


# ----------------------------------------------------------------------- problem
def eta_prime(eta: float) -> float:
    """eta -> eta' (from the independent NumPy reference model)."""
    sys.path.insert(0, str(ROOT / "tests" / "reference"))
    import scipy_model

    return float(scipy_model.eta_prime(eta))


def params(system_dict: dict) -> np.ndarray:
    """Parameter vector [m, k12, c, c12, mu, eps, eta', v_b] of a one-disk constant-belt system."""
    d = system_dict
    if int(d["n_oscillators"]) != 1 or str(d["drive"]) != "constant":
        raise ValueError("peers support one disk on a constant belt only")
    return np.array(
        [d["m"], d["k12"], d["c"], d["c12"], d["mu"], d["eps"], eta_prime(d["eta"]), d["vb"]],
        dtype=np.float64,
    )


@njit(cache=True, fastmath=False)
def rhs1(y, p, out):
    """dy/dt of one disk on a constant belt; y = [x, dx, phi, dphi]."""
    m, k12, c, c12, mu, eps, etap, vb = p[0], p[1], p[2], p[3], p[4], p[5], p[6], p[7]
    v = y[1] - vb
    w = y[3]
    s = v * v + w * w + eps * eps
    # arranged for latency as the engine's own right-hand side is (the square root beside
    # the one division, no division after the friction factor), so that the peers and
    # the engine compare as integrators (docs/performance.md, "Latency of the arithmetic")
    inv_s = 1.0 / s
    b = math.sqrt(s) * inv_s + etap * eps * eps * eps * (inv_s * inv_s)
    inv_m = 1.0 / m
    out[0] = y[1]
    out[1] = -(c * y[1] + c12 * y[3] + y[0] + k12 * y[2]) - (mu * v) * b
    out[2] = y[3]
    out[3] = (
        -(c12 * y[1] + c * y[3] + k12 * y[0] + y[2]) * inv_m - ((2.0 / 3.0) * mu * inv_m * w) * b
    )


@njit(cache=True)
def jac1(y, p, J):
    """Analytic Jacobian of :func:`rhs1` into J (4x4)."""
    m, k12, c, c12, mu, eps, etap, vb = p[0], p[1], p[2], p[3], p[4], p[5], p[6], p[7]
    v = y[1] - vb
    w = y[3]
    s = v * v + w * w + eps * eps
    rs = math.sqrt(s)
    e3 = eps * eps * eps
    b = 1.0 / rs + etap * e3 / (s * s)
    db = -0.5 / (s * rs) - 2.0 * etap * e3 / (s * s * s)
    t_v = b + 2.0 * v * v * db
    t_w = 2.0 * v * w * db
    m_v = (2.0 / 3.0) * 2.0 * v * w * db
    m_w = (2.0 / 3.0) * (b + 2.0 * w * w * db)
    for i in range(4):
        for j in range(4):
            J[i, j] = 0.0
    J[0, 1] = 1.0
    J[1, 0] = -1.0
    J[1, 1] = -(c + mu * t_v)
    J[1, 2] = -k12
    J[1, 3] = -(c12 + mu * t_w)
    J[2, 3] = 1.0
    J[3, 0] = -k12 / m
    J[3, 1] = -(c12 + mu * m_v) / m
    J[3, 2] = -1.0 / m
    J[3, 3] = -(c + mu * m_w) / m


@njit(cache=True)
def grid_crossings(t, y, p, t_min):
    """Upward zero crossings of y[:, 1] on an output grid, refined on cubic Hermite interpolants.

    Returns (t_points, points) for crossings at t >= t_min. Two RHS calls and a few
    safeguarded Newton iterations per crossing.
    """
    n = y.shape[1]
    cnt = 0
    for k in range(len(t) - 1):
        if y[k, 1] < 0.0 and y[k + 1, 1] >= 0.0:
            cnt += 1
    tp = np.empty(cnt)
    pts = np.empty((cnt, n))
    f0 = np.empty(n)
    f1 = np.empty(n)
    j = 0
    for k in range(len(t) - 1):
        a1 = y[k, 1]
        b1 = y[k + 1, 1]
        if not (a1 < 0.0 and b1 >= 0.0):
            continue
        h = t[k + 1] - t[k]
        rhs1(y[k], p, f0)
        rhs1(y[k + 1], p, f1)
        lo, hi = 0.0, 1.0
        s = a1 / (a1 - b1)
        for _ in range(50):
            s2 = s * s
            s3 = s2 * s
            g = (
                (2 * s3 - 3 * s2 + 1) * a1
                + (s3 - 2 * s2 + s) * h * f0[1]
                + (-2 * s3 + 3 * s2) * b1
                + (s3 - s2) * h * f1[1]
            )
            if g < 0.0:
                lo = s
            else:
                hi = s
            dg = (
                (6 * s2 - 6 * s) * a1
                + (3 * s2 - 4 * s + 1) * h * f0[1]
                + (-6 * s2 + 6 * s) * b1
                + (3 * s2 - 2 * s) * h * f1[1]
            )
            sn = s - g / dg if dg != 0.0 else 0.5 * (lo + hi)
            if not (lo < sn < hi):
                sn = 0.5 * (lo + hi)
            if abs(sn - s) < 1e-15 or hi - lo < 1e-15:
                s = sn
                break
            s = sn
        s2 = s * s
        s3 = s2 * s
        h00 = 2 * s3 - 3 * s2 + 1
        h10 = s3 - 2 * s2 + s
        h01 = -2 * s3 + 3 * s2
        h11 = s3 - s2
        tc = t[k] + s * h
        if tc < t_min:
            continue
        tp[j] = tc
        for i in range(n):
            pts[j, i] = h00 * y[k, i] + h10 * h * f0[i] + h01 * y[k + 1, i] + h11 * h * f1[i]
        j += 1
    return tp[:j], pts[:j]


def output_grid(t_end: float, t_min: float, dt: float = GRID_DT) -> np.ndarray:
    """[0, t_min, t_min + dt, ..., t_end]: a grid only where points are recorded."""
    g = np.arange(t_min, t_end + 0.5 * dt, dt)
    g[-1] = min(g[-1], t_end)
    return np.concatenate(([0.0], g)) if t_min > 0.0 else g


def warm_up() -> None:
    """Compile this module's kernels outside any timing."""
    p = np.array([2.0, -0.8, 0.0, 0.0, 0.0491, 1e-5, 1.0, 0.0112])
    y = np.zeros(4)
    out = np.empty(4)
    J = np.empty((4, 4))
    rhs1(y, p, out)
    jac1(y, p, J)
    grid_crossings(np.linspace(0, 1, 3), np.zeros((3, 4)), p, 0.0)


# -------------------------------------------------------------------- numbalsoda
def numbalsoda_available() -> tuple[bool, str]:
    try:
        import numbalsoda  # noqa: F401
    except Exception as exc:  # noqa: BLE001
        return False, f"import numbalsoda failed: {exc!r}"
    return True, ""


_NBL = {}


def numbalsoda_funcptr() -> int:
    """Address of a numba cfunc with numbalsoda's signature calling :func:`rhs1`."""
    if "ptr" not in _NBL:
        import numba
        from numbalsoda import lsoda_sig

        @numba.cfunc(lsoda_sig)
        def f(t, u_, du_, p_):
            u = numba.carray(u_, (4,))
            du = numba.carray(du_, (4,))
            p = numba.carray(p_, (8,))
            rhs1(u, p, du)

        _NBL["cfunc"] = f
        _NBL["ptr"] = f.address
    return _NBL["ptr"]


def numbalsoda_counting_funcptr() -> int:
    """As :func:`numbalsoda_funcptr`, but each call adds 1 to ``data[8]`` (data: p, then 0)."""
    if "count_ptr" not in _NBL:
        import numba
        from numbalsoda import lsoda_sig

        @numba.cfunc(lsoda_sig)
        def f(t, u_, du_, p_):
            u = numba.carray(u_, (4,))
            du = numba.carray(du_, (4,))
            d = numba.carray(p_, (9,))
            rhs1(u, d[:8], du)
            d[8] += 1.0

        _NBL["count_cfunc"] = f
        _NBL["count_ptr"] = f.address
    return _NBL["count_ptr"]


def numbalsoda_rhs_evaluations(p, t_end, t_min, rtol, atol, dt=GRID_DT) -> int:
    """RHS calls of the :func:`numbalsoda_run` run with points (its FD Jacobian's included).

    LSODA's work counters are not returned by numbalsoda, so the RHS counts its own calls.
    """
    from numbalsoda import lsoda

    data = np.append(np.asarray(p, dtype=float), 0.0)
    g = output_grid(t_end, t_min, dt)
    lsoda(numbalsoda_counting_funcptr(), np.zeros(4), g, data=data, rtol=rtol, atol=atol,
          mxstep=MXSTEP)  # fmt: skip
    return int(data[8])


def numbalsoda_run(p, t_end, t_min, rtol, atol, integrate_only=False, dt=GRID_DT):
    """numbalsoda LSODA (its internal finite-difference Jacobian); returns (ok, t_pts, pts)."""
    from numbalsoda import lsoda

    ptr = numbalsoda_funcptr()
    y0 = np.zeros(4)
    if integrate_only:
        usol, ok = lsoda(
            ptr, y0, np.array([0.0, t_end]), data=p, rtol=rtol, atol=atol, mxstep=MXSTEP
        )
        return ok, np.empty(0), np.empty((0, 4))
    g = output_grid(t_end, t_min, dt)
    usol, ok = lsoda(ptr, y0, g, data=p, rtol=rtol, atol=atol, mxstep=MXSTEP)
    tp, pts = grid_crossings(g, usol, p, t_min)
    return ok, tp, pts


_NBL_SWEEP = {}


def numbalsoda_sweep_kernel():
    """``@njit(parallel=True)`` sweep: numbalsoda's lsoda inside a prange loop + grid crossings."""
    if "k" in _NBL_SWEEP:
        return _NBL_SWEEP["k"]
    from numbalsoda import lsoda

    @njit(parallel=True)
    def sweep(ptr, P, grid, t_min, rtol, atol, max_points):
        nv = P.shape[0]
        counts = np.zeros(nv, np.int64)
        ok = np.zeros(nv, np.bool_)
        T = np.full((nv, max_points), np.nan)
        Y = np.full((nv, max_points, 4), np.nan)
        amp = np.zeros(nv)
        for i in prange(nv):
            y0 = np.zeros(4)
            p = P[i].copy()
            usol, success = lsoda(ptr, y0, grid, data=p, rtol=rtol, atol=atol, mxstep=100_000_000)
            ok[i] = success
            a = 0.0
            for r in range(len(grid)):
                if grid[r] >= t_min:
                    a = max(a, abs(usol[r, 1]), abs(usol[r, 3]))
            amp[i] = a
            tp, pts = grid_crossings(grid, usol, p, t_min)
            k = min(len(tp), max_points)
            counts[i] = len(tp)
            # keep the LAST max_points points
            off = len(tp) - k
            for j in range(k):
                T[i, j] = tp[off + j]
                for c in range(4):
                    Y[i, j, c] = pts[off + j, c]
        return ok, counts, T, Y, amp

    _NBL_SWEEP["k"] = sweep
    return sweep


# ------------------------------------------------------------------------- SciPy
def scipy_run(p, t_end, t_min, method, rtol, atol, integrate_only=False, cap=60.0, amplitude=False):
    """solve_ivp with the compiled RHS/Jacobian and SciPy's own event location.

    Returns (status, t_pts, pts), plus the motion amplitude max |dx1|, |dphi1| over the
    steps after t_min if ``amplitude``; status "timeout" after ``cap`` seconds.
    """
    from scipy.integrate import solve_ivp

    class _Timeout(Exception):
        pass

    t0 = time.perf_counter()
    calls = [0]

    def f(t, y):
        calls[0] += 1
        if calls[0] % 5000 == 0 and time.perf_counter() - t0 > cap:
            raise _Timeout
        out = np.empty(4)
        rhs1(y, p, out)
        return out

    def jac(t, y):
        J = np.empty((4, 4))
        jac1(y, p, J)
        return J

    def ev(t, y):
        return y[1]

    ev.direction = 1
    kw = dict(jac=jac) if method in ("Radau", "BDF", "LSODA") else {}
    if not integrate_only:
        kw["events"] = ev
    try:
        sol = solve_ivp(f, (0.0, t_end), np.zeros(4), method=method, rtol=rtol, atol=atol, **kw)
    except _Timeout:
        return ("timeout", np.empty(0), np.empty((0, 4))) + ((None,) if amplitude else ())
    if sol.status != 0:
        fail = (f"failed: {sol.message}", np.empty(0), np.empty((0, 4)))
        return fail + ((None,) if amplitude else ())
    if integrate_only:
        return "ok", np.empty(0), np.empty((0, 4))
    te = np.asarray(sol.t_events[0])
    ye = np.asarray(sol.y_events[0]).reshape(-1, 4)
    keep = (te >= t_min) & (te > 0.0)
    if amplitude:
        w = sol.t >= t_min
        amp = float(np.max(np.abs(sol.y[[1, 3]][:, w])))
        return "ok", te[keep], ye[keep], amp
    return "ok", te[keep], ye[keep]


# ------------------------------------------------------------------ SUNDIALS CVODE
def sundae_available() -> tuple[bool, str]:
    try:
        import sksundae  # noqa: F401
    except Exception as exc:  # noqa: BLE001
        return False, f"import sksundae failed: {exc!r}"
    return True, ""


@njit(cache=True)
def _cv_rhs(t, y, yp, ud):
    rhs1(y, ud[0], yp)


@njit(cache=True)
def _cv_jac(t, y, yp, J, ud):
    jac1(y, ud[0], J)


@njit(cache=True)
def _cv_event(t, y, ev, ud):
    ev[0] = y[1]


def cvode_run(p, t_end, t_min, rtol, atol, integrate_only=False, amplitude=False):
    """SUNDIALS CVODE BDF (dense direct solver, analytic Jacobian) via scikit-sundae.

    Callbacks are the compiled ``@njit`` functions (called through Python by the
    Cython wrapper); crossings from CVODE's own rootfinding. Returns (status, t_pts, pts).
    ``userdata`` is the tuple ``(p,)``: scikit-sundae 1.2 tests ``if userdata`` and so
    rejects a bare NumPy array.
    """
    from sksundae.cvode import CVODE

    kw = dict(
        method="BDF", rtol=rtol, atol=atol, jacfn=_cv_jac, userdata=(p,),
        linsolver="dense", max_num_steps=MXSTEP,
    )  # fmt: skip
    if not integrate_only:
        _cv_event.direction = [1]
        _cv_event.terminal = [False]
        kw.update(eventsfn=_cv_event, num_events=1)
    solver = CVODE(_cv_rhs, **kw)
    # amplitude: outputs every 0.05 over the window (CVODE interpolates them)
    tspan = output_grid(t_end, t_min, 0.05) if amplitude else np.array([0.0, 0.5 * t_end, t_end])
    sol = solver.solve(tspan, np.zeros(4))
    if not sol.success:
        fail = (f"failed: {sol.message}", np.empty(0), np.empty((0, 4)))
        return fail + ((None,) if amplitude else ())
    if integrate_only:
        return "ok", np.empty(0), np.empty((0, 4))
    if sol.t_events is None:
        te, ye = np.empty(0), np.empty((0, 4))
    else:
        te = np.asarray(sol.t_events, dtype=float).ravel()
        ye = np.asarray(sol.y_events, dtype=float).reshape(-1, 4)
    keep = (te >= t_min) & (te > 0.0)
    if amplitude:
        ys = np.asarray(sol.y).reshape(len(sol.t), 4)
        w = np.asarray(sol.t) >= t_min
        return "ok", te[keep], ye[keep], float(np.max(np.abs(ys[w][:, [1, 3]])))
    return "ok", te[keep], ye[keep]


# ------------------------------------------------------------------ diffrax (JAX)
def diffrax_available() -> tuple[bool, str]:
    try:
        import diffrax  # noqa: F401
        import jax  # noqa: F401
    except Exception as exc:  # noqa: BLE001
        return False, f"import diffrax/jax failed: {exc!r}"
    return True, ""


_DFX = {}


def _diffrax_solver(kind: str):
    """jitted (and for kind="vmap", vmapped over the parameter vector) Kvaerno5 solve.

    Signature: fn(p, rtol, atol, ts) -> (ys on ts, number of accepted steps, result code).
    ``ts`` = None-equivalent is not allowed under jit, so "end" returns only y(t_end).
    """
    key = kind
    if key in _DFX:
        return _DFX[key]
    import jax

    jax.config.update("jax_enable_x64", True)
    import diffrax
    import jax.numpy as jnp

    def f(t, y, p):
        m, k12, c, c12, mu, eps, etap, vb = p[0], p[1], p[2], p[3], p[4], p[5], p[6], p[7]
        v = y[1] - vb
        w = y[3]
        s = v * v + w * w + eps * eps
        b = 1.0 / jnp.sqrt(s) + etap * eps**3 / (s * s)
        return jnp.stack(
            [
                y[1],
                -(c * y[1] + c12 * y[3] + y[0] + k12 * y[2] + mu * v * b),
                y[3],
                -(c12 * y[1] + c * y[3] + k12 * y[0] + y[2] + mu * (2.0 / 3.0) * w * b) / m,
            ]
        )

    term = diffrax.ODETerm(f)
    solver = diffrax.Kvaerno5()

    def solve(p, rtol, atol, ts):
        sol = diffrax.diffeqsolve(
            term, solver, t0=0.0, t1=ts[-1], dt0=1e-4, y0=jnp.zeros(4), args=p,
            saveat=diffrax.SaveAt(ts=ts),
            stepsize_controller=diffrax.PIDController(rtol=rtol, atol=atol),
            max_steps=10_000_000, throw=False,
        )  # fmt: skip
        return sol.ys, sol.stats["num_accepted_steps"], sol.result._value

    fn = (
        jax.jit(solve)
        if kind == "single"
        else jax.jit(jax.vmap(solve, in_axes=(0, None, None, None)))
    )
    _DFX[key] = fn
    return fn


def diffrax_run(p, t_end, t_min, rtol, atol, integrate_only=False, dt=GRID_DT):
    """Kvaerno5 (jitted); points from the output grid by :func:`grid_crossings`."""
    import jax.numpy as jnp

    fn = _diffrax_solver("single")
    ts = np.array([t_end]) if integrate_only else output_grid(t_end, t_min, dt)
    ys, nacc, res = fn(jnp.asarray(p), rtol, atol, jnp.asarray(ts))
    ys = np.asarray(ys)
    ok = int(res) == 0
    if integrate_only or not ok:
        return ("ok" if ok else f"failed: result {int(res)}"), np.empty(0), np.empty((0, 4))
    tp, pts = grid_crossings(ts, ys, p, t_min)
    return "ok", tp, pts


def diffrax_warm(P, n_ts, chunk=50):
    """Compile the vmapped solve for a chunk of ``chunk`` values and an n_ts-point grid
    (on a tiny time span, so the call itself is cheap)."""
    import jax.numpy as jnp

    fn = _diffrax_solver("vmap")
    Pc = np.repeat(P[:1], chunk, axis=0)
    fn(jnp.asarray(Pc), 1e-6, 1e-8, jnp.asarray(np.linspace(0.0, 1e-3, n_ts)))


def diffrax_sweep(
    P, t_end, t_min, rtol, atol, dt=GRID_DT, chunk=50, max_points=256, budget_s=math.inf
):
    """Kvaerno5 jitted and vmapped over the rows of P (in chunks, to bound the grid's memory).

    Stops after the chunk that makes the projected total exceed ``budget_s``; ``done``
    (the number of values solved) is returned last.
    """
    import jax.numpy as jnp

    fn = _diffrax_solver("vmap")
    ts = output_grid(t_end, t_min, dt)
    nv = P.shape[0]
    ok = np.zeros(nv, bool)
    counts = np.zeros(nv, np.int64)
    T = np.full((nv, max_points), np.nan)
    Y = np.full((nv, max_points, 4), np.nan)
    amp = np.zeros(nv)
    win = ts >= t_min
    t_start = time.perf_counter()
    done = 0
    for a in range(0, nv, chunk):
        if done and (time.perf_counter() - t_start) * nv / done > budget_s:
            break
        b = min(nv, a + chunk)
        Pc = P[a:b]
        if b - a < chunk:  # same shape for every chunk: no recompilation
            Pc = np.concatenate([Pc, np.repeat(Pc[-1:], chunk - (b - a), axis=0)])
        ys, nacc, res = fn(jnp.asarray(Pc), rtol, atol, jnp.asarray(ts))
        ys = np.asarray(ys)
        res = np.asarray(res)
        for i in range(a, b):
            ok[i] = int(res[i - a]) == 0
            amp[i] = float(np.max(np.abs(ys[i - a][win][:, [1, 3]])))
            tp, pts = grid_crossings(ts, ys[i - a], P[i], t_min)
            counts[i] = len(tp)
            k = min(len(tp), max_points)
            T[i, :k] = tp[len(tp) - k :]
            Y[i, :k] = pts[len(tp) - k :]
        done = b
    return ok, counts, T, Y, amp, done
