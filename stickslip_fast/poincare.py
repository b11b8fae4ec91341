"""Poincare section at the local minima of x_1, period detection, run classification.

The section is dx_1 = 0 crossed upwards. The crossing inside an accepted step
is located by Illinois regula falsi on the step's dense output, to round-off.

Equilibria (steady sliding, a stalled motor) make dx_1 flicker around zero at
round-off level and would produce spurious "period-1" points; runs are
therefore classified from the amplitude of the motion over the recording
window (:func:`classify`), never from the points.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from .integrators import dense_value

_JIT = dict(cache=True, nogil=True)

STATUS_NAMES = (
    "ok",
    "equilibrium",
    "stalled",
    "no-crossings",
    "nonfinite",
    "step-underflow",
    "max-steps",
)
ST_OK, ST_EQUILIBRIUM, ST_STALLED, ST_NO_CROSSINGS, ST_NONFINITE, ST_UNDERFLOW, ST_MAX_STEPS = (
    range(7)
)
#: Statuses for which a run has an orbit to report.
ORBIT_STATUSES = ("ok",)

#: A DC-motor equilibrium counts as "stalled" when the belt runs slower than
#: this fraction of its no-load speed v_b0.
STALL_FRACTION = 0.01


@njit(**_JIT)
def locate_upcrossing(kind: int, y0, y1, D, comp: int) -> float:
    """theta in [0, 1] where component ``comp`` of the dense output crosses 0.

    Requires y0[comp] < 0 <= y1[comp]. Illinois method: superlinear, bracketing,
    stops when the bracket no longer shrinks in floating point.
    """
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
        f = dense_value(kind, theta, y0, y1, D, comp)
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


@njit(**_JIT)
def detect_period(points: np.ndarray, count: int, tol: float, max_period: int) -> int:
    """Smallest p <= max_period such that the last p points repeat p earlier.

    ``points`` holds ``count`` points in time order. Period p needs at least
    2p points, and every one of the last p points must lie within ``tol``
    (max norm, scaled by 1 + the largest |coordinate|) of the point p before it.
    Returns 0 if no such p exists.
    """
    if count < 2:
        return 0
    n = points.shape[1]
    scale = 0.0
    for j in range(count):
        for i in range(n):
            v = abs(points[j, i])
            if v > scale:
                scale = v
    thr = tol * (1.0 + scale)
    pmax = min(max_period, count // 2)
    for per in range(1, pmax + 1):
        good = True
        for j in range(count - per, count):
            for i in range(n):
                if abs(points[j, i] - points[j - per, i]) > thr:
                    good = False
                    break
            if not good:
                break
        if good:
            return per
    return 0


@njit(**_JIT)
def motion_measure(ymin: np.ndarray, ymax: np.ndarray, n_osc: int, dc: bool) -> float:
    """How far the run is from rest over the recording window.

    The largest |dx_i| or |dphi_i| of any disk, or the range of the DC motor's
    belt speed v_b: zero exactly when the disks are at rest and the belt runs
    steadily (steady sliding, or a stalled motor).
    """
    amp = 0.0
    for i in range(n_osc):
        for j in (4 * i + 1, 4 * i + 3):
            if ymax[j] >= ymin[j]:
                amp = max(amp, abs(ymin[j]), abs(ymax[j]))
    if dc:
        j = 4 * n_osc
        if ymax[j] >= ymin[j]:
            amp = max(amp, ymax[j] - ymin[j])
    return amp


@njit(**_JIT)
def classify(
    amplitude: float,
    n_crossings: int,
    dc: bool,
    vb_end: float,
    vb0: float,
    equilibrium_tol: float,
) -> int:
    """Status of a run that reached t_end, from the motion over the window.

    ``amplitude`` is :func:`motion_measure` over the recording window. The run
    is at rest if it is <= ``equilibrium_tol``: every disk velocity stays that
    close to 0 and the belt speed varies by less. (Positions are not used: in
    the smooth friction law "sticking" is a slow creep, so a stalled disk still
    drifts by ~1e-3 over thousands of time units, at velocities of O(eps).) A
    disk stuck to a moving belt (dx = v_b) is moving, not at rest. At rest on a DC
    motor with |v_b| <= STALL_FRACTION * |v_b0| is "stalled", otherwise
    "equilibrium". Moving without a single crossing is "no-crossings".
    """
    if amplitude <= equilibrium_tol:
        if dc and abs(vb_end) <= STALL_FRACTION * abs(vb0):
            return ST_STALLED
        return ST_EQUILIBRIUM
    if n_crossings == 0:
        return ST_NO_CROSSINGS
    return ST_OK
