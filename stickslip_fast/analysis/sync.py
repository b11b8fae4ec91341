"""Synchronization of oscillators: phases from Poincare events, phase locking, sync error.

:func:`phases_from_events` gives each disk a phase from its own Poincare events
(local minima of x_i), the phase differences relative to disk 1, a classification
("in-phase", "anti-phase", "desynchronized") and the Kuramoto order parameter.
:func:`sync_error` is a cheap sweep-level measure from the Poincare points alone.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

__all__ = ["SyncResult", "event_times", "phases_from_events", "sync_error", "wrap_phase"]


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
        Largest ``|wrap(phase_diff - mean_diff)|`` of each row (drift / locking test).
    labels : list of str
        Per oscillator (index 0 is oscillator 1, "reference").
    classification : str
        "in-phase" or "anti-phase" if every other oscillator is, else
        "desynchronized" (also for mixed labels with N > 2: "mixed").
    order_parameter : float
        Kuramoto R = time average of ``|mean_i exp(i theta_i)|`` over ``t``.
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
        Tolerance in radians: "in-phase" if ``|mean diff|`` < tol, "anti-phase" if
        ``|mean diff - pi|`` < tol, in both cases only if the differences stay
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
    labels, classification = _lock_labels(mean, spread, tol)
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


def _lock_labels(mean: np.ndarray, spread: np.ndarray, tol: float) -> tuple[list[str], str]:
    """Each oscillator's locking to the first (from its mean phase difference and spread), and
    the classification of the whole."""
    n_oscillators = len(mean)
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
    return labels, classification


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
