"""The stick phases of a periodic orbit (durations per disk), sampled over one period."""

from __future__ import annotations

import math

import numpy as np

from ..analysis.simulate import simulate
from ..model.system import System
from .returnmap import _finite_state

#: A disk sticks while its slip speed sqrt((dx - v_b)^2 + dphi^2) is below this many
#: eps (the friction law's regularisation; 100 eps = 1e-3 at the presets): far below
#: the slip speeds of a slip phase, far above the creep inside a stick phase.
STICK_SPEED = 100.0


def stick_phases(
    system: System,
    point: np.ndarray,
    T: float,
    *,
    threshold: float = STICK_SPEED,
    n_samples: int = 20000,
    rtol: float = 1e-10,
    atol: float = 1e-12,
    starts: np.ndarray | None = None,
) -> np.ndarray:
    """The stick phases of a periodic orbit: their durations, one per phase and disk.

    Integrates one period T from ``point`` (on the orbit) and samples it
    ``n_samples`` times. A disk sticks while its slip speed
    sqrt((dx_i - v_b)^2 + dphi_i^2) is below ``threshold`` eps; a stick phase is a
    maximal run of sticking samples, counted cyclically (a phase across t = 0 = T
    is one phase). For N disks the phases of every disk are listed.

    Parameters
    ----------
    system : System
    point : array_like, shape (n_state,)
        A state on the orbit (e.g. ``orbit.points[0]``).
    T : float
        The period in time.
    threshold : float
        Stick speed in units of ``system.eps`` (:data:`STICK_SPEED`).
    n_samples : int
        Samples per period; phases shorter than T / n_samples may be missed.
    rtol, atol : float
        Integration tolerances.
    starts : ndarray, shape (m, n_state), optional
        The states at times 0, T/m, ..., (m - 1) T/m (the segment starts of
        multiple shooting, ``starts[0]`` = ``point``): each piece is sampled from
        its own start, so that an unstable orbit's rounding is not amplified over
        the whole period. ``n_samples`` is rounded up to a multiple of m.

    Returns
    -------
    ndarray
        The durations of the stick phases (its length is their number; empty
        for a pure slip orbit; ``[T]`` for a disk that never slips).

    Raises
    ------
    ValueError
        For a non-finite or non-positive T, or a state of the wrong size.
    """
    y0 = _finite_state("point", point, system.n_state)
    if not (math.isfinite(T) and T > 0):
        raise ValueError(f"T must be a finite number > 0, got {T!r}")
    pieces = [y0] if starts is None else list(np.asarray(starts, dtype=float))
    m = len(pieces)
    per = -(-n_samples // m)
    n_samples = per * m
    dt = T / n_samples
    ys = []
    for y_start in pieces:
        r = simulate(system, T / m, y0=y_start, sample_dt=dt, rtol=rtol, atol=atol, max_points=1)
        ys.append(r.y[:per])
        if ys[-1].shape[0] < per or not np.all(np.isfinite(ys[-1])):
            raise ValueError(
                f"the orbit could not be sampled over one period (status {r.status!r})"
            )
    return _phase_durations(system, np.concatenate(ys), T, dt, threshold)


def slip_velocity(system: System, y: np.ndarray, disk: int) -> tuple:
    """(u1, u2): ``disk``'s (0-based) velocity relative to its belt in the states y
    (n_state,) or (k, n_state); a stick phase is where hypot(u1, u2) < threshold eps."""
    vb = y[..., -1] if system.is_dc_motor else system.vb
    return y[..., 4 * disk + 1] - vb, y[..., 4 * disk + 3]


def _phase_durations(system: System, y: np.ndarray, T: float, dt: float, threshold: float):
    """The stick phases' durations in the samples y (one period, step dt), disk by disk."""
    n = system.n_oscillators
    out = []
    for i in range(n):
        speed = np.hypot(*slip_velocity(system, y, i))
        stick = speed < threshold * system.eps
        if stick.all():
            out.append(float(T))
            continue
        # cyclic runs: start at a slipping sample so that no run wraps around
        k0 = int(np.argmin(stick))
        st = np.roll(stick, -k0)
        edges = np.flatnonzero(np.diff(np.r_[0, st.astype(np.int8), 0]))
        out.extend(float((b - a) * dt) for a, b in zip(edges[::2], edges[1::2]))
    return np.array(out)
