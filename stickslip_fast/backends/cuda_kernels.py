"""The CUDA kernels of the GPU backend: each thread integrates trajectories one after another.

Imported only through :mod:`stickslip_fast.backends.cuda` (which schedules the
launches), and only when ``backend="cuda"`` is asked for: nothing else in the
package imports CUDA.

What runs on the device
-----------------------
A thread takes runs (one value from its start) from an atomic counter, one after the
other, and advances its current run by one step per pass of its loop; so a warp's
lanes keep stepping together while their runs differ in length. Each run is
integrated with Rodas5P (coefficients
from :data:`stickslip_fast.core.tableaus.RODAS5P`, frozen into the kernel as
constant data), the analytic Jacobian and the bordered O(N) linear solve, the
same PI step-size controller as the CPU kernel, an inline Poincare detector
(upward zero of dx1 located on the step's dense output by Illinois regula
falsi), the fixed or the converged stop rule, and the same classification.
Per-thread workspaces are ``cuda.local.array`` with sizes fixed at compile
time: one kernel is compiled per (N, drive, register cap), for
``N <= MAX_OSCILLATORS``.

One source of the equations
---------------------------
The kernel calls :func:`stickslip_fast.model.equations.rhs`,
:func:`~stickslip_fast.model.equations.jacobian_blocks`, the bordered solve
:func:`stickslip_fast.model.linalg.w_factor` / :func:`~stickslip_fast.model.linalg.w_solve`
and the helpers of :mod:`stickslip_fast.core.poincare` (:func:`motion_measure`,
:func:`classify`, :func:`orbit_period`, :func:`ring_period`) *as they are*:
numba-cuda compiles a CPU ``@njit`` function called from a kernel into a
device function from the same Python source (``CUDATypingContext.resolve_value_type``
wraps the dispatcher's ``py_func`` in a device ``CUDADispatcher``, recursively
for the functions it calls, such as :func:`~stickslip_fast.model.equations.friction_partials`).
There is no second copy of the model to drift. Only the step loop is written
here: the CPU's generic driver allocates its workspaces and dispatches through
CPU-target ``@overload``s, which device code cannot use. It mirrors
:func:`stickslip_fast.core.driver.drive` with the Rodas5P stepper, the Poincare
observer and the stop rules (and the classification of ``trajectory._run``)
operation for operation; the tests compare the two value by value.
"""

from __future__ import annotations

import math

import numpy as np

from ..core.steppers import PI_ALPHA, PI_BETA, STEP_FAC_MAX, STEP_FAC_MIN, STEP_SAFETY
from ..core.tableaus import RODAS5P
from ..core.trajectory import CONVERGED_MIN_POINTS, CONVERGED_MIN_REPEATS
from .cuda_device import (  # numba.cuda from there: it imports numba_cuda first
    _ST_ERROR,
    _ST_MAX_STEPS,
    _ST_NONFINITE,
    _ST_OK,
    _ST_UNDERFLOW,
    _classify_end,
    _dense_value,
    _disks_at_rest,
    _error_norm,
    _initial_step,
    _locate_upcrossing,
    _nan_rows,
    _time_order,
    _undecided,
    _write_counts,
    check_available,
    cuda,
    float64,
    int64,
    jacobian_blocks,
    orbit_period,
    rhs,
    ring_period,
    simulator_enabled,
    w_factor,
    w_solve,
)

__all__ = ["MAX_OSCILLATORS", "check_available", "get_kernel", "simulator_enabled"]


#: Largest chain the kernels are specialised for; larger N runs on the CPU.
MAX_OSCILLATORS = 4


# Rodas5P as data: numba freezes module-level arrays into the kernel as constants.
_GAMMA = float(RODAS5P.gamma)
_A = np.ascontiguousarray(RODAS5P.a, dtype=np.float64)
_C = np.ascontiguousarray(RODAS5P.C, dtype=np.float64)
_B = np.ascontiguousarray(RODAS5P.b, dtype=np.float64)
_E = np.ascontiguousarray(RODAS5P.b_err, dtype=np.float64)
_H = np.ascontiguousarray(RODAS5P.H, dtype=np.float64)
_Q = RODAS5P.embedded_order + 1.0


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
        dwell, points, t_points, ints, t_conv, final_state, queue)``: one run per
        row ``v`` of ``params``, from row ``v`` of ``y0`` (or its only row), taken
        by the threads from ``queue`` (an int64 device array holding 0): any
        number of threads does all the runs, with the same results; the
        outputs have the layout of :func:`stickslip_fast.core.sweep_kernels.sweep_chunk`.
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
    NST = int(_B.size)
    NDN = int(_H.shape[0])
    MIN_REPEATS = CONVERGED_MIN_REPEATS
    MIN_POINTS = CONVERGED_MIN_POINTS
    jit = cuda.jit if max_registers is None else cuda.jit(max_registers=max_registers)

    # One function on purpose: a kernel's per-thread state lives in its registers and
    # local arrays, which device functions could only share through more local memory.
    @jit
    def sweep_kernel(
        y0, params, t_end, t_transient, rtol, atol, h_fixed, max_steps, equilibrium_tol,
        period_tol, max_period, converged, dwell, points, t_points, ints, t_conv, final_state,
        queue,
    ):  # fmt: skip
        n_runs = params.shape[0]
        if n_runs == 0:
            return
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

        # A persistent thread: it takes the next run from ``queue`` (an atomic counter)
        # whenever its run ends, and every pass of the loop below advances its run by
        # one step. A warp's lanes so keep stepping together while their runs differ in
        # length, instead of idling until the longest run of the warp ends. A run's
        # arithmetic does not depend on the thread that does it.
        v = -1
        running = False
        row0 = 0
        p = params[0]
        pts = points[0]
        tpts = t_points[0]
        cap = pts.shape[0]
        n_steps = 0
        n_rej = 0
        n_cross = 0
        status = _ST_OK
        t = 0.0
        t_stop = 0.0
        h = 0.0
        adaptive = True
        err_prev = 1.0
        last_rejected = False
        jac_fresh = False
        jcorner = 0.0
        phase = 0
        rest_since = math.nan
        d1_rest_since = math.nan
        last_cross = math.nan
        checked = -1
        target = 0
        while True:
            if not running:
                if v >= 0:  # the run that just ended
                    # ---- classification, as trajectory._run / _lane_values
                    for i in range(NS):
                        final_state[v, i] = y[i]
                    if status == _ST_OK:  # (the host passes t_transient = 0 if converged)
                        status = _classify_end(
                            t, rest_since, d1_rest_since, last_cross, dwell, t_transient, y, DC, p
                        )
                    count = 0
                    period = 0
                    if status == _ST_OK:
                        count = min(n_cross, cap)
                        _time_order(pts, tpts, n_cross)
                        period = orbit_period(pts, count, period_tol, max_period, p, N_OSC, DC)
                    _nan_rows(pts, tpts, count)
                    _write_counts(ints, v, count, period, status, n_steps, n_rej, n_cross)
                v = cuda.atomic.add(queue, 0, 1)
                if v >= n_runs:
                    return
                row0 = v if y0.shape[0] > 1 else 0
                # eta' is filled in on the host. (Copying the row into a local array
                # costs registers and spills, per ptxas: scripts/cuda_ptx_report.py.)
                p = params[v]
                pts = points[v]
                tpts = t_points[v]
                cap = pts.shape[0]
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
                    _nan_rows(pts, tpts, 0)
                    for i in range(NS):
                        final_state[v, i] = y[i]
                    _write_counts(ints, v, 0, 0, _ST_ERROR, 0, 0, 0)
                    v = -1  # written: no classification for this run
                    continue

                n_steps = 0
                n_rej = 0
                n_cross = 0
                status = _ST_OK
                t = 0.0
                t_stop = t_end  # moved by a look past the end, as stoprules.past_end

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
                # converged stopping (stoprules.converged_stop, operation for operation)
                phase = 0  # 1: converged, recording the last points
                rest_since = math.nan
                d1_rest_since = math.nan
                last_cross = math.nan
                checked = -1
                target = 0
                if not converged:  # a start at rest is at rest from t = 0, as stoprules.reset_stop
                    at_rest0 = _disks_at_rest(y, N_OSC, equilibrium_tol)
                    if abs(y[1]) <= equilibrium_tol and abs(y[3]) <= equilibrium_tol:
                        d1_rest_since = 0.0
                    if at_rest0:
                        rest_since = 0.0
                        for i in range(NS):
                            wmin[i] = y[i]
                            wmax[i] = y[i]

                running = t < t_end
                if not running:
                    continue
            for _step in range(1):  # one step; "break" ends the run, "continue" the step
                if n_steps >= max_steps or n_rej >= max_steps:
                    status = _ST_MAX_STEPS
                    running = False
                    break
                if t + h >= t_stop or (adaptive and t + 1.01 * h >= t_stop):
                    h = t_stop - t
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
                        running = False
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
                        h *= max(STEP_FAC_MIN, STEP_SAFETY * en ** (-1.0 / _Q))
                    last_rejected = True
                    # "not >=" also catches a step size that is not a number
                    if not (h >= 1e-14 * max(1.0, abs(t))):
                        status = _ST_UNDERFLOW if ok else _ST_NONFINITE
                        running = False
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
                        last_cross = t1  # the step's end, as stoprules.time_since_crossing
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
                    fac = STEP_SAFETY * en_c ** (-PI_ALPHA / _Q) * err_prev ** (PI_BETA / _Q)
                    fac = min(STEP_FAC_MAX, max(STEP_FAC_MIN, fac))
                    if last_rejected:
                        fac = min(fac, 1.0)
                    h *= fac
                    err_prev = max(en, 1e-10)
                    last_rejected = False
                # ---- rest, tracked always (the classification reads it), as stoprules.track_rest
                if abs(y[1]) <= equilibrium_tol and abs(y[3]) <= equilibrium_tol:
                    if math.isnan(d1_rest_since):
                        d1_rest_since = t
                else:
                    d1_rest_since = math.nan
                at_rest = _disks_at_rest(y, N_OSC, equilibrium_tol)
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
                if phase == 2:  # past the window's end, as stoprules.past_end
                    if not _undecided(t, rest_since, d1_rest_since, last_cross, dwell, t_transient):
                        running = False
                        break
                    continue
                if not converged:
                    continue
                # ---- converged stopping, as stoprules.converged_now
                if phase == 1:  # ends where disk 1 moves, as stoprules.converged_now
                    if n_cross >= target and (
                        math.isnan(d1_rest_since) or (at_rest and t - rest_since >= dwell)
                    ):
                        running = False
                        break
                    continue
                if at_rest and t - rest_since >= dwell:
                    for i in range(NS):  # the recording window is the dwell window
                        ymin[i] = wmin[i]
                        ymax[i] = wmax[i]
                    t_conv[v] = rest_since
                    running = False
                    break
                if n_cross != checked:  # repeating points: checked once per new crossing
                    checked = n_cross
                    per = ring_period(pts, n_cross, period_tol, max_period, MIN_REPEATS, MIN_POINTS)
                    if per > 0:  # (then the ring holds at least 9 points)
                        target = min(cap, max(MIN_POINTS, 4 * per))
                        # not the round-off flicker of dx1 at rest (disk 1 at rest since the
                        # previous crossing, as stoprules.converged_now), and
                        # time left to record the points (ditto)
                        flicker = at_rest and not d1_rest_since > tpts[(n_cross - 2) % cap]
                        last = tpts[(n_cross - 1) % cap]
                        pace = (last - tpts[(n_cross - 1 - per) % cap]) / per
                        if not flicker and t + (target + 1) * pace <= t_end:
                            phase = 1
                            t_conv[v] = t
                            n_cross = 0  # a fresh recording window from here
                            checked = 0
                            for i in range(NS):
                                ymin[i] = y[i]
                                ymax[i] = y[i]
            if running and not t < t_stop:  # the window's last step, as stoprules.past_end
                running = phase != 2 and _undecided(
                    t, rest_since, d1_rest_since, last_cross, dwell, t_transient
                )
                if running:
                    phase = 2
                    t_stop += dwell

    return sweep_kernel
