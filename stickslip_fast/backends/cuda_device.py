"""What the CUDA kernels stand on: numba-cuda's import, the device functions they call, status codes.

The model, the classification and the bordered linear algebra are the CPU's own ``@njit``
functions (:func:`_device_callable`: numba-cuda compiles the same source for the device); the
helpers below are device-only (error norm, initial step, dense output, crossing location).
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

# numba.cuda only once numba_cuda is imported (above)
from numba import cuda, float64, int64, types  # noqa: F401  (cuda_kernels takes them from here)

from ..base.status import STATUS_NAMES
from ..core import poincare, stoprules
from ..model import equations as model
from ..model import linalg
from ..model.params import P_VB0

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


_ST_OK = STATUS_NAMES.index("ok")


_ST_NONFINITE = STATUS_NAMES.index("nonfinite")


_ST_UNDERFLOW = STATUS_NAMES.index("step-underflow")


_ST_MAX_STEPS = STATUS_NAMES.index("max-steps")


_ST_ERROR = STATUS_NAMES.index("error")


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


orbit_period = _device_callable(poincare.orbit_period)


ring_period = _device_callable(poincare.ring_period)


undecided = _device_callable(poincare.undecided)


# the stop rules' rest and crossing times: t - since, or a default while unset (NaN)
_elapsed = _device_callable(stoprules._elapsed)


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


@cuda.jit(device=True)
def _time_order(pts, tpts, n_cross):
    """Unroll a ring of crossings into time order: rotate left by ``n_cross % cap``."""
    cap = pts.shape[0]
    if cap > 0 and n_cross > cap:
        start = n_cross % cap
        if start > 0:
            _reverse_rows(pts, tpts, 0, start)
            _reverse_rows(pts, tpts, start, cap)
            _reverse_rows(pts, tpts, 0, cap)


@cuda.jit(device=True)
def _nan_rows(pts, tpts, start):
    """Rows ``start`` .. of a run's points and times: NaN (no point there)."""
    for k in range(start, pts.shape[0]):
        tpts[k] = math.nan
        for i in range(pts.shape[1]):
            pts[k, i] = math.nan


@cuda.jit(device=True)
def _write_counts(ints, v, count, period, status, n_steps, n_rej, n_cross):
    """Row ``v`` of the integer outputs, in the order of ``SWEEP_INT_FIELDS``."""
    ints[v, 0] = count
    ints[v, 1] = period
    ints[v, 2] = status
    ints[v, 3] = n_steps
    ints[v, 4] = n_rej
    ints[v, 5] = n_cross


@cuda.jit(device=True)
def _disks_at_rest(y, n_osc, tol):
    """Every disk's speeds (x-dot, phi-dot) within ``tol``, as ``stoprules`` judges rest."""
    for i in range(n_osc):
        if not (abs(y[4 * i + 1]) <= tol and abs(y[4 * i + 3]) <= tol):
            return False
    return True


@cuda.jit(device=True)
def _undecided(t, rest_since, d1_rest_since, last_cross, dwell, t_rec):
    """``poincare.undecided`` at ``t`` of a run whose rest and crossings are tracked as
    ``stoprules`` tracks them, recording from ``t_rec``: ``stoprules.past_end``'s test."""
    rest_time = _elapsed(rest_since, t, -1.0)
    d1_rest = _elapsed(d1_rest_since, t, -1.0)
    since = _elapsed(last_cross, t, math.inf)
    return undecided(rest_time, d1_rest, since, min(dwell, t - t_rec))


@cuda.jit(device=True)
def _classify_end(t, rest_since, d1_rest_since, last_cross, dwell, t_rec, y, dc, p):
    """The status of a run that ended at ``t`` in state ``y`` with parameters ``p``, as
    ``trajectory._run`` classifies it."""
    rest_time = _elapsed(rest_since, t, -1.0)
    d1_rest = _elapsed(d1_rest_since, t, -1.0)
    since = _elapsed(last_cross, t, math.inf)
    vb_end = y[y.shape[0] - 1] if dc else 0.0
    return classify(rest_time, d1_rest, min(dwell, t - t_rec), since, dc, vb_end, p[P_VB0])
