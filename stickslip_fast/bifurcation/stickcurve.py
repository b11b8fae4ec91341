"""Curves of stick-phase events of periodic orbits in two parameters.

A disk sticks while its slip speed s(t) = sqrt((dx_i - v_b)^2 + dphi_i^2) is below
delta = threshold eps (:data:`.stickphases.STICK_SPEED`). Along a smooth family of
orbits the number of stick phases changes where a local extremum of s crosses delta: a
minimum (a stick phase appears or vanishes) or a maximum inside a stick phase (a
micro-slip splits it). At a nondegenerate extremum t* (ds/dt = 0, d2s/dt2 != 0), t* is a
smooth function of the orbit and the parameters, and so is

    E(z, l1, l2) = s(t*) - delta,

t* the extremum near the one tracked (the envelope theorem: dE = ds at fixed t*). The
curve is F(z, l1, l2) = (P(z) - z, E / |grad E|_0) = 0 in x = (section coordinates, l1,
l2), followed by :func:`.foldcurve.run_curve` (pseudo-arclength, corrector to ``tol``
a distance). P's Jacobian and parameter columns come from the variational equations
(:mod:`.returnmap`); E's gradient from central differences of E (t* solved again, from
the orbit's point on the section, at each shifted x).

t*: the trajectory from z is sampled on a window around the last t* (the extremum of the
same kind nearest it), and q(t) = u . du/dt (u = the slip velocity vector; ds^2/dt = 2 q)
is solved between the neighbouring samples by Brent's method, each trial integrated from
the state at the first of them (itself integrated from z, not interpolated). The curve ends ("lost") where that extremum is no longer found.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from ..analysis.simulate import simulate
from ..base.roots import brent_root
from ..model.system import System
from .detection import _sorted_eigs
from .foldcurve import run_curve
from .returnmap import _field
from .stickphases import STICK_SPEED, slip_velocity

#: The kind name of a stick-phase event curve (as :class:`~.branch.Bifurcation`'s).
STICK_KIND = "stick-phase"


#: The simulation statuses of a completed run (a window too short for a section crossing
#: ends with "no-crossings").
_FINE = ("ok", "no-crossings")


@dataclass
class StickEvent:
    """The slip-speed extremum a stick-phase event is made of: ``disk`` (0-based),
    ``extremum`` ("min": a stick phase appears or vanishes; "max": a micro-slip inside a
    stick phase opens or closes), ``time`` t* from the orbit's point on the section,
    ``speed`` s(t*), and the stick ``threshold`` in units of eps."""

    disk: int
    extremum: str
    time: float
    speed: float
    threshold: float = STICK_SPEED


def _slip(system: System, y: np.ndarray, disk: int) -> tuple[float, float]:
    """(s, q): the slip speed of ``disk`` at y and q = u . du/dt (= s ds/dt)."""
    f = _field(system, y)
    dvb = f[-1] if system.is_dc_motor else 0.0
    u1, u2 = slip_velocity(system, y, disk)
    return math.hypot(u1, u2), u1 * (f[4 * disk + 1] - dvb) + u2 * f[4 * disk + 3]


def _samples(system, z, t0, t1, n, rtol, atol):
    """The states at n + 1 equidistant times in [t0, t1] along the trajectory from z."""
    dt = (t1 - t0) / n
    r = simulate(system, t1 + 0.5 * dt, t_transient=t0, y0=z, sample_dt=dt, rtol=rtol,
                 atol=atol, max_points=0)  # fmt: skip
    if r.status not in _FINE or r.y.shape[0] < n + 1:
        raise ValueError(f"the orbit could not be sampled (status {r.status!r})")
    return t0 + dt * np.arange(n + 1), r.y[: n + 1]


def _state(system, z, t, rtol, atol):
    if t <= 0:
        return np.array(z, float)
    r = simulate(system, t, y0=z, rtol=rtol, atol=atol, max_points=0)
    if r.status not in _FINE:
        raise ValueError(f"the orbit could not be integrated (status {r.status!r})")
    return r.final_state


def slip_extremum(system: System, z: np.ndarray, t_guess: float, width: float, disk: int,
                  extremum: str, *, n: int = 200, rtol: float = 1e-11,
                  atol: float = 1e-13) -> tuple[float, float]:  # fmt: skip
    """(t*, s(t*)): the local ``extremum`` ("min"/"max") of ``disk``'s slip speed nearest
    ``t_guess`` on [t_guess - width, t_guess + width] along the trajectory from z
    (ValueError where there is none)."""
    t0 = max(t_guess - width, 0.0)
    t, ys = _samples(system, z, t0, t_guess + width, n, rtol, atol)
    s = np.array([_slip(system, y, disk)[0] for y in ys])
    sign = 1.0 if extremum == "min" else -1.0
    i = np.arange(1, n)
    k = i[(sign * s[i] <= sign * s[i - 1]) & (sign * s[i] <= sign * s[i + 1])]
    if not k.size:
        raise ValueError(f"no slip-speed {extremum} of disk {disk} near t = {t_guess:g}")
    k = int(k[np.argmin(np.abs(t[k] - t_guess))])

    a, b = t[k - 1], t[k + 1]
    ya = _state(system, z, a, rtol, atol)  # integrated, not the interpolated sample

    def q(tt):
        return sign * _slip(system, _state(system, ya, tt - a, rtol, atol), disk)[1]

    qa, qb = q(a), sign * _slip(system, ys[k + 1], disk)[1]
    if not (qa < 0 < qb):
        raise ValueError(f"the slip-speed {extremum} of disk {disk} is not bracketed")
    ts = brent_root(q, a, b, xtol=1e-13, rtol=4 * np.finfo(float).eps)
    return float(ts), _slip(system, _state(system, ya, ts - a, rtol, atol), disk)[0]


def nearest_stick_event(system: System, point: np.ndarray, T: float, *,
                        threshold: float = STICK_SPEED, n_samples: int = 20000,
                        rtol: float = 1e-11, atol: float = 1e-13) -> StickEvent:  # fmt: skip
    """The slip-speed extremum (any disk, minimum or maximum) of the orbit through
    ``point`` (period T) whose value is nearest the stick threshold (in log scale): at a
    located "stick-phase" bifurcation, the extremum that crosses it."""
    t, ys = _samples(system, point, 0.0, T, n_samples, rtol, atol)
    best = None
    delta = threshold * system.eps
    for disk in range(system.n_oscillators):
        s = np.array([_slip(system, y, disk)[0] for y in ys])
        i = np.arange(1, n_samples)
        for kind, sign in (("min", 1.0), ("max", -1.0)):
            for k in i[(sign * s[i] < sign * s[i - 1]) & (sign * s[i] <= sign * s[i + 1])]:
                d = abs(math.log(max(s[k], 1e-300) / delta))
                if best is None or d < best[0]:
                    best = (d, disk, kind, float(t[k]))
    if best is None:
        raise ValueError("the orbit's slip speeds have no extremum")
    _, disk, kind, tk = best
    width = 4.0 * T / n_samples
    ts, sv = slip_extremum(system, point, tk, width, disk, kind, n=8, rtol=rtol, atol=atol)
    return StickEvent(disk, kind, ts, sv, threshold)


def stick_augmented(base: Callable, system_at: Callable, full: Callable, event: StickEvent,
                    width: float, fd_step: float, rtol: float, atol: float):  # fmt: skip
    """The evaluator of F = (P(z) - z, E scale) at x = (section coordinates, l1, l2), and
    a setter of the scale: ``base`` as in :func:`.foldcurve.augmented`; ``system_at(x)``
    the system at x's parameters; ``full(x)`` the state on the section. ``event``'s time
    is updated to the last t* found (the tracking)."""
    delta = event.threshold
    box = {"scale": 1.0}

    def E(x):
        sy = system_at(x)
        ts, s = slip_extremum(sy, full(x), event.time, width, event.disk, event.extremum,
                              rtol=rtol, atol=atol)  # fmt: skip
        return ts, s - delta * sy.eps

    def evaluate(x):
        ok, R, DR, A = base(x)
        if not ok:
            return False, None, None, None
        try:
            ts, e = E(x)
            grad = np.empty(x.size)
            for k in range(x.size):
                dx = np.zeros_like(x)
                dx[k] = fd_step * max(1.0, abs(x[k]))
                grad[k] = (E(x + dx)[1] - E(x - dx)[1]) / (2 * dx[k])
        except ValueError:
            return False, None, None, None
        event.time, event.speed = ts, e + delta * system_at(x).eps
        sc = box["scale"]
        return True, np.r_[R, sc * e], np.vstack([DR, sc * grad]), A

    return evaluate, box


def follow_stick_curve(base: Callable, system_at: Callable, full: Callable, x0: np.ndarray,
                       event: StickEvent, direction: float, bounds2: tuple[float, float], *,
                       width: float, fd_step: float = 1e-6, rtol: float = 1e-11,
                       atol: float = 1e-13, **settings):  # fmt: skip
    """Follow the stick-phase event ``event`` of the orbit through x0 = (section
    coordinates, l1, l2) in (l1, l2).

    ``width``: the half-window in time where t* is looked for around its last value;
    ``fd_step``: the relative step of E's central differences; ``settings``: those of
    :func:`.foldcurve.run_curve`. Returns (xs, mults, codim2, status, times) with
    ``times`` the t* of each point; status "start-failed" where E cannot be evaluated at
    x0 (the extremum was not found)."""
    evaluate, box = stick_augmented(base, system_at, full, event, width, fd_step, rtol, atol)
    ok, _, DF, _ = evaluate(x0)
    if not ok:
        return None, None, [], "start-failed", None
    box["scale"] = 1.0 / max(float(np.linalg.norm(DF[-1])), 1e-300)
    seen: dict[bytes, float] = {}

    def recorded(x):
        out = evaluate(x)
        if out[0]:
            seen[x.tobytes()] = event.time
        return out

    xs, mults, codim2, status, _ = run_curve(recorded, x0, direction, bounds2,
                                             spectrum=_sorted_eigs, **settings)  # fmt: skip
    if xs is None:
        return None, None, [], status, None
    return xs, mults, codim2, status, np.array([seen.get(x.tobytes(), math.nan) for x in xs])
