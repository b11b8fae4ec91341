"""Poincare section at the local minima of x_1, period detection, run classification.

The section is dx_1 = 0 crossed upwards; the crossing inside an accepted step is
located on the step's dense output by :func:`driver.locate_crossing`.

Equilibria (steady sliding, a stalled motor) make dx_1 flicker around zero at
round-off level and would produce spurious "period-1" points; runs are
therefore classified from how long they have been at rest at their end
(:func:`classify`), never from the points, and never from motion that died out
before the end.
"""

from __future__ import annotations

import math

import numpy as np

from ..base.jit import JIT as _JIT
from ..base.jit import njit
from ..base.status import (  # noqa: F401  (re-exported: the codes used to live here)
    ORBIT_STATUSES,
    ST_EQUILIBRIUM,
    ST_MAX_STEPS,
    ST_NO_CROSSINGS,
    ST_NONFINITE,
    ST_OK,
    ST_STALLED,
    ST_UNDERFLOW,
    ST_UNSETTLED,
    STATUS_NAMES,
)
from ..model.equations import rest_position
from ..model.params import P_VB

#: A DC-motor equilibrium counts as "stalled" when the belt runs slower than
#: this fraction of its no-load speed v_b0.
STALL_FRACTION = 0.01

#: Longest period :func:`detect_period` looks for.
MAX_PERIOD = 64


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
    thr = tol * (1.0 + _max_abs(points, 0, count))
    for per in range(1, min(max_period, count // 2) + 1):
        if _repeats(points, count - per, count, per, thr):
            return per
    return 0


@njit(**_JIT)
def _max_abs(pts: np.ndarray, first: int, last: int) -> float:
    """Largest |coordinate| of points first..last-1 (point j in row j % rows: a ring)."""
    cap = pts.shape[0]
    scale = 0.0
    for j in range(first, last):
        row = pts[j % cap]
        for i in range(pts.shape[1]):
            v = abs(row[i])
            if v > scale:
                scale = v
    return scale


@njit(**_JIT)
def _repeats(pts: np.ndarray, first: int, last: int, per: int, thr: float) -> bool:
    """Whether each point first..last-1 lies within thr (max norm) of the point per before it."""
    cap = pts.shape[0]
    for j in range(first, last):
        a = pts[j % cap]
        b = pts[(j - per) % cap]
        for i in range(pts.shape[1]):
            if not abs(a[i] - b[i]) <= thr:
                return False
    return True


@njit(inline="always", **_JIT)
def _last_changes(pts: np.ndarray, count: int, per: int) -> tuple[float, float]:
    """(d0, d1): the largest change of a point over one period, in the period before the
    last p points and in the last p (max norm; a ring buffer, point j in row j % rows)."""
    cap = pts.shape[0]
    d0 = 0.0
    d1 = 0.0
    for j in range(count - 2 * per, count):
        a = pts[j % cap]
        b = pts[(j - per) % cap]
        for i in range(pts.shape[1]):
            if j < count - per:
                d0 = max(d0, abs(a[i] - b[i]))
            else:
                d1 = max(d1, abs(a[i] - b[i]))
    return d0, d1


#: Changes below this fraction of the period tolerance are the integration's noise: the
#: ratio of two successive ones says nothing about convergence (see :func:`ring_period`).
NOISE_FRACTION = 1e-2


#: A period is refused (:func:`orbit_period`) where the points, extrapolated to their limit,
#: come within this fraction of their present distance from rest: a decaying oscillation
#: heads for rest (fraction 0), a transient that converges onto an orbit for a point of
#: that orbit (fraction near 1).
REST_LIMIT_FRACTION = 0.5


@njit(**_JIT)
def orbit_period(
    points: np.ndarray, count: int, tol: float, max_period: int, p: np.ndarray, n_osc: int,
    dc: bool,
) -> int:  # fmt: skip
    """The period of a run's points (:func:`detect_period`), 0 for an oscillation dying out.

    A slowly decaying oscillation about a stable equilibrium has x1 minima that change
    by less than ``tol`` per period long before it comes to rest: the fixed window then
    sees them repeat. Such a period is refused (0, "none found") when the points still
    drift beyond ``tol`` and are heading for the rest state: over the last two periods
    (:func:`decays_to_rest`) or, for a decay of two modes at once, whose points change
    unevenly from period to period, over the envelope of the window's last points
    (:func:`envelope_decays`, label rules 4).
    ``p`` is the run's parameter array, ``n_osc`` its number of disks, ``dc`` its drive.
    """
    per = detect_period(points, count, tol, max_period)
    if per > 0 and decays_to_rest(points, count, per, tol, p, n_osc, dc):
        return 0
    if per > 0 and envelope_decays(points, count, per, tol, p, n_osc, dc):
        return 0
    return per


@njit(inline="always", **_JIT)  # inlined into orbit_period: one compile, not two
def decays_to_rest(
    points: np.ndarray, count: int, per: int, tol: float, p: np.ndarray, n_osc: int, dc: bool
) -> bool:
    """Whether points that repeat with period ``per`` are an oscillation dying out.

    The change over each of the last two periods, d0 then d1 (max norm), extrapolated
    geometrically as in :func:`ring_period` (rho = d1 / d0), leaves
    d1 rho / (1 - rho) to come. Where that exceeds ``tol`` (scaled as in
    :func:`detect_period`), each of the last ``per`` points is carried to its limit,
    and the points decay to rest when those limits lie within
    :data:`REST_LIMIT_FRACTION` of the points' present distance from the rest state
    (every disk at :func:`~stickslip_fast.model.equations.rest_position`, speeds 0, on a
    belt at the point's own speed). Points that do not contract (d1 >= d0), or whose
    changes are noise, are left to :func:`detect_period`'s verdict.
    """
    if count < 3 * per:
        return False
    cap = points.shape[0]
    thr = tol * (1.0 + _max_abs(points, count - 3 * per, count))
    d0, d1 = _last_changes(points, count, per)
    if d1 <= NOISE_FRACTION * thr or not d1 < d0:
        return False
    rho = d1 / d0
    ahead = rho / (1.0 - rho)
    if d1 * ahead <= thr:
        return False  # at its limit within the tolerance: the period stands
    to_rest_now = 0.0
    to_rest_limit = 0.0
    for j in range(count - per, count):
        a = points[j % cap]
        b = points[(j - per) % cap]
        vb_now = a[4 * n_osc] if dc else p[P_VB]
        vb_lim = a[4 * n_osc] + ahead * (a[4 * n_osc] - b[4 * n_osc]) if dc else p[P_VB]
        x_now, ph_now = rest_position(vb_now, p)
        x_lim, ph_lim = rest_position(vb_lim, p)
        if not (math.isfinite(x_now) and math.isfinite(x_lim)):
            return False  # |k12| = 1: no rest position to head for; the period stands
        for i in range(4 * n_osc):
            lim = a[i] + ahead * (a[i] - b[i])
            slot = i % 4
            if slot == 0:
                rest_now, rest_lim = x_now, x_lim
            elif slot == 2:
                rest_now, rest_lim = ph_now, ph_lim
            else:
                rest_now, rest_lim = 0.0, 0.0
            to_rest_now = max(to_rest_now, abs(a[i] - rest_now))
            to_rest_limit = max(to_rest_limit, abs(lim - rest_lim))
    return to_rest_limit <= REST_LIMIT_FRACTION * to_rest_now


#: :func:`envelope_decays` compares three blocks of this fraction of the recorded points
#: each, the last ones: long enough to hold several beats of two modes decaying at once.
ENVELOPE_BLOCK_FRACTION = 1.0 / 8.0
#: ... and at least this many periods each (fewer points: the rule says nothing).
ENVELOPE_MIN_PERIODS = 4


@njit(**_JIT)
def _distance_from_rest(a: np.ndarray, p: np.ndarray, n_osc: int, dc: bool) -> float:
    """Max-norm distance of the point ``a`` from rest (as in :func:`decays_to_rest`): every
    disk at :func:`~stickslip_fast.model.equations.rest_position` for the point's own belt
    speed, speeds 0; NaN where there is no rest position (|k12| = 1)."""
    x_rest, ph_rest = rest_position(a[4 * n_osc] if dc else p[P_VB], p)
    if not math.isfinite(x_rest):
        return math.nan
    dist = 0.0
    for i in range(4 * n_osc):
        slot = i % 4
        rest = x_rest if slot == 0 else (ph_rest if slot == 2 else 0.0)
        dist = max(dist, abs(a[i] - rest))
    return dist


@njit(**_JIT)
def envelope_decays(
    points: np.ndarray, count: int, per: int, tol: float, p: np.ndarray, n_osc: int, dc: bool
) -> bool:
    """Whether points that repeat with period ``per`` are two modes dying out at once.

    Where two modes of a disk ring together (x1 and phi1, coupled by k12), the slower
    one's beat makes the points change unevenly from period to period, and the
    extrapolation of :func:`decays_to_rest` over two periods does not see them head for
    rest. Here the last three blocks of :data:`ENVELOPE_BLOCK_FRACTION` of the recorded
    points each (whole periods, at least :data:`ENVELOPE_MIN_PERIODS`) give the envelope
    A1, A2, A3: the largest distance from rest in each. The points decay to rest where
    the envelope falls by more than ``tol`` (scaled as in :func:`detect_period`), with
    A1 > A2 > A3, and its geometric (Aitken) limit lies within
    :data:`REST_LIMIT_FRACTION` of A3. A transient that converges onto an orbit heads
    for that orbit's own envelope (limit / A3 >= 0.878 over the 3681 orbits of the full
    sweeps of Figs. 4, 6, 12, 14 and 16; docs/limits.md); a settled orbit has
    A1 = A2 = A3 within ``tol``.
    """
    cap = points.shape[0]
    held = min(count, cap)
    block = int(held * ENVELOPE_BLOCK_FRACTION) // per * per
    if block < ENVELOPE_MIN_PERIODS * per:
        return False
    first = count - 3 * block
    thr = tol * (1.0 + _max_abs(points, first, count))
    a1 = a2 = a3 = 0.0  # scalars, not an array: the CUDA kernels call this on the device
    for j in range(first, count):
        d = _distance_from_rest(points[j % cap], p, n_osc, dc)
        if not math.isfinite(d):
            return False  # no rest position to head for: the period stands
        if j < first + block:
            a1 = max(a1, d)
        elif j < first + 2 * block:
            a2 = max(a2, d)
        else:
            a3 = max(a3, d)
    if not (a1 - a3 > thr and a1 > a2 > a3):
        return False
    r = (a2 - a3) / (a1 - a2)
    if r >= 1.0:
        return False
    limit = a3 - (a2 - a3) * r / (1.0 - r)
    return limit <= REST_LIMIT_FRACTION * a3


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
def still_settling(rest_time: float, disk1_rest_time: float, tail: float) -> bool:
    """True while a run's label cannot be told yet: :func:`classify` says "unsettled".

    That is: the disks at rest (``rest_time`` >= 0), or disk 1 alone at rest while
    another disk moves (``disk1_rest_time`` >= 0), for less than ``tail``. A run
    that ends its window so looks past it (:func:`stoprules.past_end`).
    """
    if rest_time >= 0.0:
        return rest_time < tail
    return 0.0 <= disk1_rest_time < tail


@njit(**_JIT)
def undecided(rest_time: float, disk1_rest_time: float, since_crossing: float, tail: float) -> bool:
    """True where a run's end cannot tell its label yet; a window that ends so looks past it.

    :func:`still_settling`, or disk 1 moving with its last crossing longer than ``tail``
    ago (``since_crossing`` finite): an orbit whose x1 minima are further apart than
    the tail may be between two of them (:func:`classify` would say "no-crossings").
    See :func:`stoprules.past_end`.
    """
    if still_settling(rest_time, disk1_rest_time, tail):
        return True
    return rest_time < 0.0 and disk1_rest_time < 0.0 and tail < since_crossing < np.inf


@njit(**_JIT)
def classify(
    rest_time: float,
    disk1_rest_time: float,
    tail: float,
    since_crossing: float,
    dc: bool,
    vb_end: float,
    vb0: float,
) -> int:
    """Status of a run that reached its end, from its settled tail.

    ``rest_time`` is how long the run has been at rest at its end, < 0 if it
    is moving (at rest: every disk
    speed |dx_i|, |dphi_i| <= ``equilibrium_tol`` and the belt speed steady to
    that tolerance; :func:`stoprules.rest_time`), ``tail`` the time over which rest
    must hold: ``dwell`` or, if shorter, the whole recording window;
    ``disk1_rest_time`` the same for disk 1 alone, whose local minima of x_1
    are the section; ``since_crossing`` the time since the last recorded
    crossing (inf if none; :func:`stoprules.time_since_crossing`). Motion, and crossings, that died out
    before the tail never count.

    - at rest over the whole tail: "equilibrium", or "stalled" on a DC motor
      whose belt runs at |v_b| <= STALL_FRACTION |v_b0|;
    - at rest at the end, but for less than the tail: "unsettled" (the run came
      to rest too late to tell; its crossings are round-off minima of x_1 at
      rest, never an orbit). The stop rules first look past the end of the
      window while the run is :func:`undecided` (:func:`stoprules.past_end`);
    - moving, with disk 1 at rest over the tail (disk 1 in steady sliding
      while another disk oscillates): "no-crossings": its x_1 has round-off
      minima only; with disk 1 at rest for less than the tail: "unsettled";
    - moving at the end without a crossing in the tail: "no-crossings" (e.g.
      disk 1 at rest while disk 2 oscillates; the transient's crossings do not
      make an orbit);
    - moving at the end with crossings in the tail: "ok" (the period comes
      from the points).

    (Positions are not used: in the smooth friction law "sticking" is a slow
    creep, so a stalled disk still drifts by ~1e-3 over thousands of time
    units, at velocities of O(eps). A disk stuck to a moving belt, dx = v_b, is
    moving, not at rest.)
    """
    if rest_time >= 0.0 and rest_time >= tail:
        if dc and abs(vb_end) <= STALL_FRACTION * abs(vb0):
            return ST_STALLED
        return ST_EQUILIBRIUM
    if still_settling(rest_time, disk1_rest_time, tail):
        return ST_UNSETTLED
    if disk1_rest_time >= tail:
        return ST_NO_CROSSINGS
    if not since_crossing <= tail:
        return ST_NO_CROSSINGS
    return ST_OK


@njit(**_JIT)
def ring_period(
    pts: np.ndarray, count: int, tol: float, max_period: int, min_repeats: int, min_points: int
) -> int:
    """Smallest p <= max_period with which the last points of a ring buffer repeat.

    ``pts`` is a ring buffer holding the most recent of ``count`` points (point
    j in slot j % capacity). Period p is accepted when each of the last
    m = max(min_points, max(2, min_repeats) * p) points lies within ``tol`` (max
    norm, scaled by 1 + the largest |coordinate| of the points compared) of the
    point p before it, so the m + p most recent points must be in the buffer, and
    the points have stopped drifting: the change still to come, extrapolated
    geometrically from the last two periods, is within ``tol`` too. Returns 0 if
    no such p exists (also when p repeats but drifts). Used by converged stopping.
    """
    cap = pts.shape[0]
    avail = min(count, cap)
    for per in range(1, max_period + 1):
        m = max(min_points, max(2, min_repeats) * per)  # the drift test needs 2 periods
        if m + per > avail:
            break
        thr = tol * (1.0 + _max_abs(pts, count - m - per, count))
        if _repeats(pts, count - m, count, per, thr):
            # Have the points stopped drifting? After a change d0 over one period and d1
            # over the next, a geometric contraction rho = d1 / d0 leaves about
            # d1 rho / (1 - rho) to come (the stopping rule of linearly convergent
            # iterations): a slowly decaying oscillation about an equilibrium has minima
            # that change by less than thr per period long before they stop. Changes
            # below NOISE_FRACTION thr are noise, whose ratio says nothing. (Inlined in
            # Numba's IR, not a compiled helper: each compiled level costs every first run
            # its compile.)
            d0, d1 = _last_changes(pts, count, per)
            if d1 <= NOISE_FRACTION * thr:
                return per
            if not d1 < d0:
                return 0  # not contracting: its multiples would drift the same way
            rho = d1 / d0
            return per if d1 * rho / (1.0 - rho) <= thr else 0
    return 0
