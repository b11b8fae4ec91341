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
    mesh: np.ndarray | None = None,
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
        The segment starts of multiple shooting (``starts[0]`` = ``point``): each
        segment is sampled from its own start, so that an unstable orbit's rounding
        is not amplified over the whole period.
    mesh : ndarray, shape (m + 1,), optional
        With ``starts``: the segments' cuts as fractions of T, from 0 to 1 (segment
        i runs over [mesh[i] T, mesh[i + 1] T], as ``Orbit.segments`` and
        :class:`.multishoot.MultiShooting` cut them); default even cuts. Each
        segment gets at least its share of the ``n_samples`` samples.

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
    cuts = _cuts(mesh, len(pieces))
    ys, dts = [], []
    for y_start, frac in zip(pieces, np.diff(cuts)):
        # the segment's samples: n at spacing dt = frac T / n, from its own start
        n = max(1, math.ceil(frac * n_samples))
        dt = frac * T / n
        r = simulate(system, frac * T, y0=y_start, sample_dt=dt, rtol=rtol, atol=atol,
                     max_points=1)  # fmt: skip
        ys.append(r.y[:n])
        dts.append(np.full(n, dt))
        if ys[-1].shape[0] < n or not np.all(np.isfinite(ys[-1])):
            raise ValueError(
                f"the orbit could not be sampled over one period (status {r.status!r})"
            )
    dt = np.concatenate(dts)
    if np.all(dt == dt[0]):  # one spacing (one segment): durations as count x dt
        dt = dt[0]
    return _phase_durations(system, np.concatenate(ys), T, dt, threshold)


def _cuts(mesh, m: int) -> np.ndarray:
    """The m segments' cuts as fractions of the period (even without ``mesh``), checked."""
    if mesh is None:
        return np.linspace(0.0, 1.0, m + 1)
    cuts = np.asarray(mesh, dtype=float)
    if cuts.shape != (m + 1,) or cuts[0] != 0.0 or cuts[-1] != 1.0 or np.any(np.diff(cuts) <= 0):
        raise ValueError(
            f"mesh must be {m + 1} increasing fractions of the period from 0 to 1 (one more "
            f"than starts), got {mesh!r}"
        )
    return cuts


def slip_velocity(system: System, y: np.ndarray, disk: int) -> tuple:
    """(u1, u2): ``disk``'s (0-based) velocity relative to its belt in the states y
    (n_state,) or (k, n_state); a stick phase is where hypot(u1, u2) < threshold eps."""
    vb = y[..., -1] if system.is_dc_motor else system.vb
    return y[..., 4 * disk + 1] - vb, y[..., 4 * disk + 3]


def _phase_durations(system: System, y: np.ndarray, T: float, dt, threshold: float):
    """The stick phases' durations in the samples y (one period; sample k stands for the
    time dt[k] after it, or dt for a float), disk by disk."""
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
        if np.ndim(dt) == 0:
            out.extend(float((b - a) * dt) for a, b in zip(edges[::2], edges[1::2]))
        else:
            w = np.roll(dt, -k0)
            out.extend(float(w[a:b].sum()) for a, b in zip(edges[::2], edges[1::2]))
    return np.array(out)


#: A curve of orbits that stops where the orbit grazes the section (``dx1`` has an
#: extremum within this fraction of max |dx1| of zero) ends at a "section-grazing" point.
GRAZE_TOL = 1e-5


def section_graze_margin(system: System, point: np.ndarray, T: float,
                         n_samples: int = 200_000) -> float:  # fmt: skip
    """How near the orbit through ``point`` (period T) comes to grazing the section.

    The section is dx1 = 0 (the local minima of x1); the orbit grazes it where dx1 has
    a local extremum at zero, and a crossing appears or vanishes there. Returns the
    extremum of dx1 nearest zero over one period, in units of max |dx1| (inf for an
    orbit without one; NaN if the orbit could not be sampled).
    """
    y0 = _finite_state("point", point, system.n_state)
    r = simulate(system, T, y0=y0, sample_dt=T / n_samples, rtol=1e-11, atol=1e-13,
                 max_points=1)  # fmt: skip
    dx = r.y[:, 1]
    if dx.size < 3 or not np.all(np.isfinite(dx)):
        return math.nan
    turn = np.flatnonzero((dx[1:-1] - dx[:-2]) * (dx[2:] - dx[1:-1]) < 0) + 1
    if turn.size == 0:
        return math.inf
    return float(np.min(np.abs(dx[turn])) / np.max(np.abs(dx)))
