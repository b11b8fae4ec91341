"""The CUDA kernels of the GPU backend: one thread integrates one trajectory.

Imported only through :mod:`stickslip_fast.cuda_backend` (which schedules the
launches), and only when ``backend="cuda"`` is asked for: nothing else in the
package imports CUDA.

What runs on the device
-----------------------
One thread integrates one value from its start with Rodas5P (coefficients
from :data:`stickslip_fast.tableaus.RODAS5P`, frozen into the kernel as
constant data), the analytic Jacobian and the bordered O(N) linear solve, the
same PI step-size controller as the CPU kernel, an inline Poincare detector
(upward zero of dx1 located on the step's dense output by Illinois regula
falsi), the fixed or the converged stop rule, and the same classification.
Per-thread workspaces are ``cuda.local.array`` with sizes fixed at compile
time: one kernel is compiled per (N, drive, register cap), for
``N <= MAX_OSCILLATORS``.

One source of the equations
---------------------------
The kernel calls :func:`stickslip_fast.model.rhs`,
:func:`~stickslip_fast.model.jacobian_blocks`, the bordered solve
:func:`stickslip_fast.linalg.w_factor` / :func:`~stickslip_fast.linalg.w_solve`
and the helpers of :mod:`stickslip_fast.poincare` (:func:`motion_measure`,
:func:`classify`, :func:`detect_period`, :func:`ring_period`) *as they are*:
numba-cuda compiles a CPU ``@njit`` function called from a kernel into a
device function from the same Python source (``CUDATypingContext.resolve_value_type``
wraps the dispatcher's ``py_func`` in a device ``CUDADispatcher``, recursively
for the functions it calls, such as :func:`~stickslip_fast.model.friction_partials`).
There is no second copy of the model to drift. Only the step loop is written
here: the CPU's generic driver allocates its workspaces and dispatches through
CPU-target ``@overload``s, which device code cannot use. It mirrors
:func:`stickslip_fast.driver.drive` with the Rodas5P stepper, the Poincare
observer and the stop rules (and the classification of ``trajectory._run``)
operation for operation; the tests compare the two value by value.
"""

from __future__ import annotations

import logging
import math

import numpy as np

try:
    import numba_cuda  # noqa: F401  (the [cuda] extra; the built-in numba.cuda is deprecated)
except ImportError as exc:  # pragma: no cover - exercised only without the extra
    raise ImportError(
        'backend="cuda" needs numba-cuda: pip install "stickslip_fast[cuda]"'
    ) from exc

from numba import cuda, float64, int64, types

from . import linalg, model, poincare
from .params import P_VB0
from .status import STATUS_NAMES
from .steppers import PI_ALPHA, PI_BETA, STEP_FAC_MAX, STEP_FAC_MIN, STEP_SAFETY
from .tableaus import RODAS5P
from .trajectory import CONVERGED_MIN_POINTS, CONVERGED_MIN_REPEATS

# numba-cuda <= 0.30.4 registers an overload for np.row_stack when it compiles
# its first kernel, and NumPy 2.5 removed that alias: the compile then fails with
# AttributeError (seen on an H200 image with numpy 2.5.2). Restore the alias.
if not hasattr(np, "row_stack"):  # noqa: NPY201
    setattr(np, "row_stack", np.vstack)  # noqa: B010


class _NotReadyFilter(logging.Filter):
    """numba logs every cuEventQuery that answers "not ready yet" at ERROR level;
    polling launches for completion asks exactly that, so those records are dropped."""

    def filter(self, record: logging.LogRecord) -> bool:
        return "CUDA_ERROR_NOT_READY" not in record.getMessage()


logging.getLogger("numba.cuda.cudadrv.driver").addFilter(_NotReadyFilter())

__all__ = [
    "MAX_OSCILLATORS",
    "check_available",
    "compile_ptx",
    "get_kernel",
    "kernel_signature",
    "simulator_enabled",
]

#: Largest chain the kernels are specialised for; larger N runs on the CPU.
MAX_OSCILLATORS = 4

_ST_OK = STATUS_NAMES.index("ok")
_ST_NONFINITE = STATUS_NAMES.index("nonfinite")
_ST_UNDERFLOW = STATUS_NAMES.index("step-underflow")
_ST_MAX_STEPS = STATUS_NAMES.index("max-steps")
_ST_ERROR = STATUS_NAMES.index("error")

# Rodas5P as data: numba freezes module-level arrays into the kernel as constants.
_GAMMA = float(RODAS5P.gamma)
_A = np.ascontiguousarray(RODAS5P.a, dtype=np.float64)
_C = np.ascontiguousarray(RODAS5P.C, dtype=np.float64)
_B = np.ascontiguousarray(RODAS5P.b, dtype=np.float64)
_E = np.ascontiguousarray(RODAS5P.b_err, dtype=np.float64)
_H = np.ascontiguousarray(RODAS5P.H, dtype=np.float64)
_Q = RODAS5P.embedded_order + 1.0
_STAGES = int(_B.size)
_NDENSE = int(_H.shape[0])

# PI step-size controller: the CPU kernel's constants
_SAFETY = STEP_SAFETY
_FAC_MIN = STEP_FAC_MIN
_FAC_MAX = STEP_FAC_MAX
_PI_ALPHA = PI_ALPHA
_PI_BETA = PI_BETA


def simulator_enabled() -> bool:
    """True when numba runs CUDA kernels in its Python simulator (NUMBA_ENABLE_CUDASIM=1).

    Decided by which ``numba.cuda`` was imported (the variable is read once, at
    that import), not by the environment now.
    """
    return cuda.jit.__module__.startswith("numba.cuda.simulator")


def check_available() -> None:
    """Raise a RuntimeError that says so when there is no usable GPU (nor the simulator)."""
    if simulator_enabled():
        return
    if not cuda.is_available():
        raise RuntimeError(
            'backend="cuda" needs an NVIDIA GPU with a working driver, and none was found '
            "(numba.cuda.is_available() is False). Use backend='local', or set "
            "NUMBA_ENABLE_CUDASIM=1 before starting Python to run the CUDA kernels in "
            "numba's (slow) simulator for testing."
        )


def _device_callable(func):
    """A CPU ``@njit`` function as the kernels call it.

    On a GPU that is the dispatcher itself: numba-cuda compiles it into a
    device function from the same source. Numba's simulator instead runs the
    kernel as Python and calls the CPU-compiled function, which cannot take the
    simulator's array wrappers, so these are unwrapped first.
    """
    if not simulator_enabled():
        return func
    from numba.cuda.simulator.cudadrv.devicearray import (
        FakeCUDAArray,
        FakeWithinKernelCUDAArray,
    )

    def unwrap(a):
        if isinstance(a, FakeWithinKernelCUDAArray):
            a = a.__dict__["_item"]
        if isinstance(a, FakeCUDAArray):
            a = a._ary
        return a

    def call(*args):
        return func(*[unwrap(a) for a in args])

    call.__name__ = func.__name__
    return call


# the model's one source of the equations, and the CPU kernel's classification
rhs = _device_callable(model.rhs)
jacobian_blocks = _device_callable(model.jacobian_blocks)
motion_measure = _device_callable(poincare.motion_measure)
classify = _device_callable(poincare.classify)
detect_period = _device_callable(poincare.detect_period)
ring_period = _device_callable(poincare.ring_period)
# the bordered O(N) factorisation and solve of W = sigma I - J
w_factor = _device_callable(linalg.w_factor)
w_solve = _device_callable(linalg.w_solve)


# ------------------------------------------------------------ device helpers
@cuda.jit(device=True)
def _error_norm(err, y0, y1, rtol, atol):
    n = err.size
    acc = 0.0
    for i in range(n):
        sc = atol + rtol * max(abs(y0[i]), abs(y1[i]))
        e = err[i] / sc
        acc += e * e
    return math.sqrt(acc / n)


@cuda.jit(device=True)
def _initial_step(y0, f0, p, n_osc, dc, rtol, atol, order, work, fwork):
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


@cuda.jit(device=True)
def _dense_value(theta, y0, y1, D, i):
    """Rodas5P's Hermite-form dense output, component i at theta in [0, 1]."""
    inner = 0.0
    for r in range(D.shape[0] - 1, -1, -1):
        inner = D[r, i] + theta * inner
    th1 = 1.0 - theta
    return th1 * y0[i] + theta * (y1[i] + th1 * inner)


@cuda.jit(device=True)
def _locate_upcrossing(y0, y1, D, comp):
    """theta where component ``comp`` of the dense output crosses 0 upwards (Illinois)."""
    a = 0.0
    fa = y0[comp]
    b = 1.0
    fb = y1[comp]
    if fb == 0.0:
        return 1.0
    side = 0
    theta = 1.0
    for _ in range(200):
        theta = (a * fb - b * fa) / (fb - fa)
        if not (a < theta < b):
            theta = 0.5 * (a + b)
            if not (a < theta < b):
                break
        f = _dense_value(theta, y0, y1, D, comp)
        if f == 0.0:
            return theta
        if f < 0.0:
            a = theta
            fa = f
            if side == -1:
                fb *= 0.5
            side = -1
        else:
            b = theta
            fb = f
            if side == 1:
                fa *= 0.5
            side = 1
        if b - a <= 4e-16:
            break
    return theta


@cuda.jit(device=True)
def _reverse_rows(pts, tpts, lo, hi):
    """Reverse rows lo .. hi-1 of pts and tpts in place."""
    hi -= 1
    while lo < hi:
        for i in range(pts.shape[1]):
            tmp = pts[lo, i]
            pts[lo, i] = pts[hi, i]
            pts[hi, i] = tmp
        tt = tpts[lo]
        tpts[lo] = tpts[hi]
        tpts[hi] = tt
        lo += 1
        hi -= 1


# ------------------------------------------------------------------- kernels
_KERNELS: dict = {}


def get_kernel(n_osc: int, dc: bool, max_registers: int | None = None):
    """The sweep kernel specialised (workspace sizes) for ``n_osc`` disks and the drive.

    Parameters
    ----------
    n_osc : int
        Number of disks, 1 .. MAX_OSCILLATORS.
    dc : bool
        True for the DC-motor drive (one extra state, v_b).
    max_registers : int, optional
        Cap on registers per thread passed to the CUDA compiler (more threads
        resident, at the price of spills); None lets it choose. Results do not
        depend on it.

    Returns
    -------
    numba CUDA dispatcher
        ``kernel[blocks, threads](y0, params, t_end, t_transient, rtol, atol,
        h_fixed, max_steps, equilibrium_tol, period_tol, max_period, converged,
        dwell, points, t_points, ints, t_conv, final_state)``: one thread per row
        of ``params``, starting from row ``v`` of ``y0`` (or its only row); the
        outputs have the layout of :func:`stickslip_fast.trajectory.sweep_chunk`.
        ``converged`` selects the converged stop rule (then pass
        ``t_transient = 0``, as the CPU kernel records from t = 0).
    """
    n_osc = int(n_osc)
    dc = bool(dc)
    if not 1 <= n_osc <= MAX_OSCILLATORS:
        raise ValueError(f"n_osc must be in 1..{MAX_OSCILLATORS} for the CUDA kernels, got {n_osc}")
    if max_registers is not None:
        max_registers = int(max_registers)
        if simulator_enabled():  # the simulator's jit takes no register cap
            max_registers = None
    key = (n_osc, dc, max_registers)
    if key not in _KERNELS:
        _KERNELS[key] = _make_kernel(n_osc, dc, max_registers)
    return _KERNELS[key]


def _make_kernel(N_OSC: int, DC: bool, max_registers: int | None = None):  # noqa: N803
    NS = 4 * N_OSC + (1 if DC else 0)
    NST = _STAGES
    NDN = _NDENSE
    MIN_REPEATS = CONVERGED_MIN_REPEATS
    MIN_POINTS = CONVERGED_MIN_POINTS
    jit = cuda.jit if max_registers is None else cuda.jit(max_registers=max_registers)

    @jit
    def sweep_kernel(
        y0, params, t_end, t_transient, rtol, atol, h_fixed, max_steps, equilibrium_tol,
        period_tol, max_period, converged, dwell, points, t_points, ints, t_conv, final_state,
    ):  # fmt: skip
        v = cuda.grid(1)
        if v >= params.shape[0]:
            return
        row0 = v if y0.shape[0] > 1 else 0
        # eta' is filled in on the host. (Copying the row into a local array
        # costs registers and spills, per ptxas: scripts/cuda_ptx_report.py.)
        p = params[v]
        pts = points[v]
        tpts = t_points[v]
        cap = pts.shape[0]

        y = cuda.local.array(NS, float64)
        ynew = cuda.local.array(NS, float64)
        ytmp = cuda.local.array(NS, float64)
        ftmp = cuda.local.array(NS, float64)
        f0 = cuda.local.array(NS, float64)
        err = cuda.local.array(NS, float64)
        ymin = cuda.local.array(NS, float64)
        ymax = cuda.local.array(NS, float64)
        wmin = cuda.local.array(NS, float64)  # converged stopping: the rest window
        wmax = cuda.local.array(NS, float64)
        K = cuda.local.array((NST, NS), float64)
        D = cuda.local.array((NDN, NS), float64)
        jb = cuda.local.array((N_OSC, 4, 4), float64)
        jcol = cuda.local.array((N_OSC, 4), float64)
        jrow = cuda.local.array((N_OSC, 4), float64)
        lu = cuda.local.array((N_OSC, 4, 4), float64)
        piv = cuda.local.array((N_OSC, 4), int64)
        z = cuda.local.array((N_OSC, 4), float64)
        for i in range(N_OSC):
            for r in range(4):
                jcol[i, r] = 0.0
                jrow[i, r] = 0.0
                z[i, r] = 0.0
        for i in range(NS):
            y[i] = y0[row0, i]
            ymin[i] = math.inf
            ymax[i] = -math.inf

        t_conv[v] = math.nan
        # parameters or start not finite: "error", as the CPU kernel
        bad = False
        for i in range(p.shape[0]):
            if not math.isfinite(p[i]):
                bad = True
        for i in range(NS):
            if not math.isfinite(y[i]):
                bad = True
        if bad:
            for k in range(cap):
                tpts[k] = math.nan
                for i in range(NS):
                    pts[k, i] = math.nan
            for i in range(NS):
                final_state[v, i] = y[i]
            ints[v, 0] = 0
            ints[v, 1] = 0
            ints[v, 2] = _ST_ERROR
            ints[v, 3] = 0
            ints[v, 4] = 0
            ints[v, 5] = 0
            return

        n_steps = 0
        n_rej = 0
        n_cross = 0
        status = _ST_OK
        t = 0.0

        rhs(y, p, N_OSC, DC, f0)
        if t_transient <= 0.0:
            for i in range(NS):
                ymin[i] = y[i]
                ymax[i] = y[i]

        adaptive = h_fixed <= 0.0
        if adaptive:
            h = _initial_step(y, f0, p, N_OSC, DC, rtol, atol, _Q - 1.0, ytmp, ftmp)
            h = min(h, t_end)
        else:
            h = h_fixed
        err_prev = 1.0
        last_rejected = False
        jac_fresh = False
        jcorner = 0.0
        # converged stopping (driver.converged_stop, operation for operation)
        phase = 0  # 1: converged, recording the last points
        rest_since = math.nan
        d1_rest_since = math.nan
        last_cross = math.nan
        checked = -1
        target = 0
        if not converged:  # a start at rest is at rest from t = 0, as driver._reset_stop
            at_rest0 = True
            for i in range(N_OSC):
                if not (
                    abs(y[4 * i + 1]) <= equilibrium_tol and abs(y[4 * i + 3]) <= equilibrium_tol
                ):
                    at_rest0 = False
            if abs(y[1]) <= equilibrium_tol and abs(y[3]) <= equilibrium_tol:
                d1_rest_since = 0.0
            if at_rest0:
                rest_since = 0.0
                for i in range(NS):
                    wmin[i] = y[i]
                    wmax[i] = y[i]

        while t < t_end:
            if n_steps >= max_steps or n_rej >= max_steps:
                status = _ST_MAX_STEPS
                break
            if t + h >= t_end or (adaptive and t + 1.01 * h >= t_end):
                h = t_end - t
            if not jac_fresh:
                jcorner = jacobian_blocks(y, p, N_OSC, DC, jb, jcol, jrow)
                jac_fresh = True

            # ---- one Rosenbrock step (transformed form), as steppers.rosenbrock_step
            ok = True
            schur = w_factor(1.0 / (h * _GAMMA), jb, jcol, jrow, jcorner, N_OSC, DC, lu, piv, z)
            if not math.isfinite(schur):
                ok = False
            if ok:
                inv_h = 1.0 / h
                for st in range(NST):
                    if st == 0:
                        for i in range(NS):
                            ftmp[i] = f0[i]
                    else:
                        for i in range(NS):
                            acc = 0.0
                            for j in range(st):
                                acc += _A[st, j] * K[j, i]
                            ytmp[i] = y[i] + acc
                        rhs(ytmp, p, N_OSC, DC, ftmp)
                    for i in range(NS):
                        acc = 0.0
                        for j in range(st):
                            acc += _C[st, j] * K[j, i]
                        K[st, i] = ftmp[i] + inv_h * acc
                    w_solve(lu, piv, z, jrow, schur, N_OSC, DC, K[st])
                    for i in range(NS):
                        if not math.isfinite(K[st, i]):
                            ok = False
                    if not ok:
                        break
            if ok:
                for i in range(NS):
                    acc = 0.0
                    e = 0.0
                    for j in range(NST):
                        acc += _B[j] * K[j, i]
                        e += _E[j] * K[j, i]
                    ynew[i] = y[i] + acc
                    err[i] = e
                for i in range(NS):
                    if not math.isfinite(ynew[i]):
                        ok = False
            # ---- error control
            en = 0.0
            if not adaptive:
                if not ok:
                    status = _ST_NONFINITE
                    break
            elif ok:
                en = _error_norm(err, y, ynew, rtol, atol)
                if not math.isfinite(en):
                    ok = False
            if adaptive and (not ok or en > 1.0):
                n_rej += 1
                if not ok:
                    h *= 0.25
                else:
                    h *= max(_FAC_MIN, _SAFETY * en ** (-1.0 / _Q))
                last_rejected = True
                # "not >=" also catches a step size that is not a number
                if not (h >= 1e-14 * max(1.0, abs(t))):
                    status = _ST_UNDERFLOW if ok else _ST_NONFINITE
                    break
                continue

            # ---- accepted: Poincare crossing on the dense output, window amplitude
            n_steps += 1
            t1 = t + h
            if y[1] < 0.0 <= ynew[1]:
                for r in range(NDN):
                    for i in range(NS):
                        acc = 0.0
                        for j in range(NST):
                            acc += _H[r, j] * K[j, i]
                        D[r, i] = acc
                theta = _locate_upcrossing(y, ynew, D, 1)
                tc = t + theta * h
                if tc >= t_transient:
                    if cap > 0:
                        slot = n_cross % cap
                        for i in range(NS):
                            pts[slot, i] = _dense_value(theta, y, ynew, D, i)
                        tpts[slot] = tc
                    n_cross += 1
                    last_cross = t1  # the step's end, as driver.time_since_crossing
            if t1 >= t_transient:
                for i in range(NS):
                    vv = ynew[i]
                    if vv < ymin[i]:
                        ymin[i] = vv
                    if vv > ymax[i]:
                        ymax[i] = vv
            t = t + h
            for i in range(NS):
                y[i] = ynew[i]
            rhs(y, p, N_OSC, DC, f0)
            jac_fresh = False
            if adaptive:
                en_c = max(en, 1e-10)
                fac = _SAFETY * en_c ** (-_PI_ALPHA / _Q) * err_prev ** (_PI_BETA / _Q)
                fac = min(_FAC_MAX, max(_FAC_MIN, fac))
                if last_rejected:
                    fac = min(fac, 1.0)
                h *= fac
                err_prev = max(en, 1e-10)
                last_rejected = False
            # ---- rest, tracked always (the classification reads it), as driver._track_rest
            if abs(y[1]) <= equilibrium_tol and abs(y[3]) <= equilibrium_tol:
                if math.isnan(d1_rest_since):
                    d1_rest_since = t
            else:
                d1_rest_since = math.nan
            at_rest = True
            for i in range(N_OSC):
                if not (
                    abs(y[4 * i + 1]) <= equilibrium_tol and abs(y[4 * i + 3]) <= equilibrium_tol
                ):
                    at_rest = False
            if at_rest:
                if math.isnan(rest_since):
                    rest_since = t
                    for i in range(NS):
                        wmin[i] = y[i]
                        wmax[i] = y[i]
                else:
                    for i in range(NS):
                        wmin[i] = min(wmin[i], y[i])
                        wmax[i] = max(wmax[i], y[i])
                    if DC and wmax[NS - 1] - wmin[NS - 1] > equilibrium_tol:
                        rest_since = t
                        for i in range(NS):
                            wmin[i] = y[i]
                            wmax[i] = y[i]
            else:
                rest_since = math.nan
            if not converged:
                continue
            # ---- converged stopping, as driver._converged_now
            if phase == 1:
                if n_cross >= target:
                    break
                continue
            if at_rest and t - rest_since >= dwell:
                for i in range(NS):  # the recording window is the dwell window
                    ymin[i] = wmin[i]
                    ymax[i] = wmax[i]
                t_conv[v] = rest_since
                break
            if n_cross != checked:  # repeating points: checked once per new crossing
                checked = n_cross
                per = ring_period(pts, n_cross, period_tol, max_period, MIN_REPEATS, MIN_POINTS)
                # at rest, dx1 flickers around 0 and gives repeating "points"
                if per > 0 and not at_rest:
                    phase = 1
                    t_conv[v] = t
                    target = min(cap, max(MIN_POINTS, 4 * per))
                    n_cross = 0  # a fresh recording window from here
                    checked = 0
                    for i in range(NS):
                        ymin[i] = y[i]
                        ymax[i] = y[i]

        # ---- classification, as trajectory._run / _lane_values
        for i in range(NS):
            final_state[v, i] = y[i]
        if status == _ST_OK:
            vb_end = y[NS - 1] if DC else 0.0
            rest_time = -1.0 if math.isnan(rest_since) else t - rest_since
            tail = min(dwell, t - t_transient)  # the host passes t_transient = 0 if converged
            d1_rest = -1.0 if math.isnan(d1_rest_since) else t - d1_rest_since
            since = math.inf if math.isnan(last_cross) else t - last_cross
            status = classify(rest_time, d1_rest, tail, since, DC, vb_end, p[P_VB0])
        count = 0
        period = 0
        if status == _ST_OK:
            count = min(n_cross, cap)
            # unroll the ring into time order: rotate left by n_cross % cap
            if cap > 0 and n_cross > cap:
                start = n_cross % cap
                if start > 0:
                    _reverse_rows(pts, tpts, 0, start)
                    _reverse_rows(pts, tpts, start, cap)
                    _reverse_rows(pts, tpts, 0, cap)
            period = detect_period(pts, count, period_tol, max_period)
        else:
            count = 0
        for k in range(count, cap):
            tpts[k] = math.nan
            for i in range(NS):
                pts[k, i] = math.nan
        ints[v, 0] = count
        ints[v, 1] = period
        ints[v, 2] = status
        ints[v, 3] = n_steps
        ints[v, 4] = n_rej
        ints[v, 5] = n_cross

    return sweep_kernel


def kernel_signature():
    """The argument types of the sweep kernels (as launched by the backend)."""
    a1, a2, a3, i2 = float64[::1], float64[:, ::1], float64[:, :, ::1], int64[:, ::1]
    f, i = float64, int64
    b = types.boolean
    return (a2, a2, f, f, f, f, f, i, f, f, i, b, f, a3, a2, i2, a1, a2)


def compile_ptx(n_osc: int, dc: bool, cc: tuple[int, int] = (9, 0)) -> str:
    """PTX of a sweep kernel for compute capability ``cc``, compiled without a GPU.

    Needs NVVM (``pip install "stickslip_fast[cuda]"`` brings it) but no driver:
    it checks that the kernels, and the model functions they call, compile for
    the real CUDA target, which the simulator cannot. numba-cuda asks the
    current device for its compute capability when it compiles a called
    function; that question is answered with ``cc`` for the duration.

    Parameters
    ----------
    n_osc, dc : int, bool
        As for :func:`get_kernel`.
    cc : (int, int)
        Target compute capability (default 9.0, Hopper).

    Returns
    -------
    str
        The PTX text (feed it to ``ptxas -v`` for registers per thread).
    """
    if simulator_enabled():
        raise RuntimeError("compile_ptx needs the real CUDA target, not NUMBA_ENABLE_CUDASIM=1")
    import types as _types
    from unittest import mock

    from numba.cuda import dispatcher

    kernel = get_kernel(n_osc, dc)
    fake = _types.SimpleNamespace(compute_capability=tuple(cc))
    with mock.patch.object(dispatcher, "get_current_device", lambda: fake):
        ptx, _ = cuda.compile_ptx(kernel.py_func, kernel_signature(), cc=tuple(cc))
    return ptx
