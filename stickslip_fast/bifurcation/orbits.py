"""Periodic orbits by Newton on the Poincare map, their Floquet multipliers, and equilibria.

The section is the engine's Poincare section: dx1 = 0 crossed upwards (the
local minima of x1). A point on it has n - 1 free coordinates (every state
component but dx1, which is 0). The p-th return map P^p takes such a point to
the state at the p-th upward crossing; a period-p orbit is a fixed point of it.

The Jacobian of the return map (the formula, see docs/orbits.md)
-----------------------------------------------------------------
Let Phi = dy(T)/dy(0) be the state-transition matrix from a point z on the
section to the p-th crossing at time T(z), z_p = y(T), f_p = f(z_p) the vector
field there and e the unit vector of dx1 (the section normal). Differentiating
e^T y(T(z), z) = 0 gives dT/dz = -e^T Phi / (e^T f_p), so

    D P^p(z) = (I - f_p e^T / (e^T f_p)) Phi,

the monodromy corrected for the section (the flow direction at the crossing is
projected out along e). Its row for dx1 vanishes; deleting that row and the
dx1 column leaves the (n - 1) x (n - 1) Jacobian in section coordinates, whose
eigenvalues are the orbit's nontrivial Floquet multipliers (the trivial
multiplier 1 of the autonomous flow, along f, is the one the projection
removes). Intermediate crossings need no projection of their own: Phi carries
f at one crossing to f at the next, which the final projection annihilates, so
projecting once per crossing (as done here, to keep the tangents small) and
once at the end give the same matrix.

The derivative in a parameter lambda follows the same way: with s(t) = dy/dlambda
integrated from s(0) = 0 along s' = J s + df/dlambda (section coordinates held
fixed), dT/dlambda = -e^T s(T) / (e^T f_p) and

    dP^p/dlambda = (I - f_p e^T / (e^T f_p)) s(T),

projected at each crossing like the tangents (``return_map(..., param=...)``).
Continuation uses it as the last column of its Jacobian.

The tangents come from :func:`stickslip_fast.core.variational.propagate_tangents`
(the compiled Rodas5P with the exact variational Jacobian, the code the
Lyapunov exponent uses), integrated with n - 1 tangent vectors, the section's
coordinate directions.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from ..analysis.simulate import SimulationResult, simulate
from ..base.messages import plain
from ..core.settings import check_integer
from ..model.system import System
from .equilibria import (  # noqa: F401
    EQUILIBRIUM_SPEED,
    Equilibrium,
    _belt_speed,
    _sliding_guess,
    find_equilibrium,
)
from .multishoot import DEFAULT_SEGMENTS, MAX_SEGMENTS
from .multishoot_orbit import find_orbit_multiple
from .orbit_record import ORBIT_STATUSES, Orbit, multipliers_stable
from .returnmap import (  # noqa: F401
    _DEFAULT_ATOL,
    _DEFAULT_RTOL,
    _MAX_STEPS,
    _TANGENT_ATOL,
    SECTION_INDEX,
    _field,
    _finite_state,
    _minimal_period,
    _multipliers,
    _sensitivity_params,
    return_map,
)
from .stickphases import STICK_SPEED, stick_phases

__all__ = [
    "Orbit",
    "Equilibrium",
    "find_orbit",
    "find_equilibrium",
    "return_map",
    "stick_phases",
    "ORBIT_STATUSES",
    "STICK_SPEED",
]


#: The ``shooting`` choices of :func:`find_orbit` and :func:`continue_orbit`.
SHOOTING_MODES = ("single", "multiple", "auto")

#: :func:`find_orbit`'s default ``t_max`` (the longest search for the section).
DEFAULT_T_MAX = 1e4

#: :func:`find_orbit`'s default ``max_iter`` for single shooting.
SS_MAX_ITER = 30

#: :func:`find_orbit`'s default ``max_iter`` for multiple shooting: its damped corrector
#: converges linearly from a first mesh cut from one trajectory that leaves a very unstable
#: orbit within the period (about 30 steps at multiplier 1.1e8: 30 on a Xeon, 31 on an AMD
#: EPYC, where 30 ended "max-iter" at 1.02 tol). Converging runs stop as soon as they reach
#: tol, so only a failure costs more.
MS_MAX_ITER = 60


# ------------------------------------------------------------------ orbits
def _start_from(system: System, start: Any, period: int | None, t_max: float):
    """(z on the section, period) from a state, a SimulationResult or a census Attractor."""
    from ..analysis.census import Attractor

    n = system.n_state
    if isinstance(start, Attractor):
        if start.kind != "orbit" or start.period < 1:
            raise ValueError(
                f'start is a census attractor of kind {start.kind!r}; only an "orbit" '
                "has a period to find (use find_equilibrium for rest points)"
            )
        pts = np.asarray(start.points, dtype=float)
        if pts.ndim != 2 or pts.shape[1] != n or not np.all(np.isfinite(pts)):
            raise ValueError(f"start (a census attractor) has points of shape {pts.shape}, "
                             f"not (period, {n}) finite values of this system")  # fmt: skip
        return pts[0].copy(), start.period if period is None else period
    if isinstance(start, SimulationResult):
        if start.system != system:
            raise ValueError("start is a SimulationResult of a different system")
        if start.status != "ok" or start.poincare.shape[0] == 0:
            raise ValueError(
                f"start is a SimulationResult without Poincare points (status {start.status!r})"
            )
        if period is None:
            if start.period < 1:
                raise ValueError(
                    "period is None and start (a SimulationResult) has no detected period; "
                    "pass period= or simulate longer"
                )
            period = start.period
        return start.poincare[-1].copy(), period
    y = _finite_state("start", start, n)
    if period is None:
        res = simulate(system, 40 * t_max, y0=y, stop="converged", max_points=256)
        if res.status != "ok" or res.period < 1:
            raise ValueError(
                f"period is None and a simulation from start found no periodic orbit "
                f"(status {res.status!r}, period {res.period}); pass period="
            )
        return res.poincare[-1].copy(), res.period
    if y[SECTION_INDEX] != 0.0:
        # not on the section: flow to the first upward crossing
        status, pts, _, _ = return_map(system, y, 1, t_max=t_max, tangents=False)
        if status != "ok":
            raise ValueError(f"start does not reach the section dx1 = 0 (status {status!r})")
        y = pts[0]
    return y, period


#: :func:`find_orbit`'s docstring (kept out of the function body, as for
#: :func:`~stickslip_fast.analysis.census.census`: the layout rule counts a
#: function's lines, and its parameters take more lines than its code).
_FIND_ORBIT_DOC = """Find a periodic orbit by damped Newton on P^p(z) - z over the section.

Parameters
----------
system : System
start : array_like, SimulationResult or census Attractor
    A state (on the section dx1 = 0 or not: a state off it is first flowed
    to its next upward crossing), a :func:`simulate` result whose last
    Poincare point is the start (e.g. one run with ``stop="converged"``),
    or an attractor of a :func:`census` of kind "orbit" (its first point;
    ``system`` must be the census's system at that attractor's value).
period : int, optional
    p >= 1, the number of section crossings per period. Default: the
    SimulationResult's or attractor's period, or, for a state, the period a
    converged simulation from it finds.
tol : float
    Convergence: ``max |P^p(z) - z|`` <= tol over the section coordinates.
max_iter : int, optional
    Most Newton steps. Default: 30 for single shooting, :data:`MS_MAX_ITER` (60) for
    multiple shooting (also in the multiple-shooting stage of ``shooting="auto"``). Its
    damped corrector converges linearly from a first mesh cut from one trajectory that
    leaves a very unstable orbit within the period: at multiplier 1.1e8 it took 30 steps
    on a Xeon and 31 on an AMD EPYC (tests/test_multishoot.py).
rtol, atol : float
    Tolerances of the variational integration (tighter than the simulation
    defaults: the residual cannot go below the map's integration noise).
t_max : float
    Longest time allowed between two crossings.
tangent_atol : float
    Tolerance of the tangent vectors relative to their length (see
    :func:`return_map`).
shooting : {"single", "multiple", "auto"}
    "single": Newton on the return map. "multiple": the period cut evenly in
    time into ``segments`` segments joined by continuity (:mod:`.multishoot`;
    the multipliers from the segments' factors by a periodic QR scheme), for
    orbits so unstable that one integration over the period amplifies its
    rounding beyond ``tol``. "auto": single, then multiple from the same start
    where single shooting fails ("no-progress" or "max-iter": its precision
    limit, docs/limits.md).
segments : int
    m >= 1, the segments of multiple shooting (even cuts in time); those that
    amplify by more than ``multishoot.MESH_LIMIT`` are then bisected, up to
    ``max_segments``.
max_segments : int
    The most segments multiple shooting bisects into (an integer >=
    ``segments``; default ``multishoot.MAX_SEGMENTS``, 64).

Returns
-------
Orbit
    Check ``converged`` (or ``status``): a failure is returned with the last
    iterate and its residual, never as a converged orbit.

Raises
------
ValueError
    For a period < 1, a non-finite start or tolerance, or a start that
    cannot be used (naming the argument).

Notes
-----
Each step solves (D P^p - I) dz = -(P^p(z) - z) with the variational
Jacobian (docs/orbits.md) and halves the step until the residual
decreases (at most 20 halvings). At convergence the start is moved to the
crossing with the smallest x1 and Newton continues from there, so the
residual, ``jacobian`` and ``multipliers`` all refer to ``points[0]``.

Examples
--------
>>> import stickslip_fast as ssf
>>> s = ssf.System.preset("asymmetric", eta=2.0)
>>> orbit = ssf.find_orbit(s, ssf.simulate(s, 5000, stop="converged"))  # doctest: +SKIP
>>> orbit.multipliers[0].real  # doctest: +SKIP
-0.0969...
"""


def find_orbit(
    system: System,
    start: Any,
    period: int | None = None,
    *,
    tol: float = 1e-10,
    max_iter: int | None = None,
    rtol: float = _DEFAULT_RTOL,
    atol: float = _DEFAULT_ATOL,
    t_max: float = DEFAULT_T_MAX,
    tangent_atol: float = _TANGENT_ATOL,
    shooting: str = "single",
    segments: int = DEFAULT_SEGMENTS,
    max_segments: int = MAX_SEGMENTS,
) -> Orbit:
    single_iter = SS_MAX_ITER if max_iter is None else max_iter
    _check_find_args(system, period, tol, rtol, atol, t_max, tangent_atol, single_iter)
    check_shooting(shooting, segments, max_segments)
    period = None if period is None else int(period)
    z, period = _start_from(system, start, period, t_max)
    kw = dict(tol=tol, rtol=rtol, atol=atol, t_max=t_max, tangent_atol=tangent_atol)
    cuts = dict(segments=int(segments), max_segments=int(max_segments),
                max_iter=MS_MAX_ITER if max_iter is None else max_iter)  # fmt: skip
    if shooting == "multiple":
        return find_orbit_multiple(system, z, period, **cuts, **kw)
    orbit = _find_single(system, z, period, max_iter=single_iter, **kw)
    if shooting == "auto" and orbit.status in ("no-progress", "max-iter"):
        multi = find_orbit_multiple(system, z, period, **cuts, **kw)
        if multi.converged or multi.residual < orbit.residual:
            return multi
    return orbit


find_orbit.__doc__ = _FIND_ORBIT_DOC


def check_shooting(shooting: str, segments: int, max_segments: int | None = None) -> None:
    """Check the ``shooting``, ``segments`` (and ``max_segments``) arguments of
    :func:`find_orbit` and :func:`~stickslip_fast.bifurcation.orbit_branch.continue_orbit`.

    Raises
    ------
    ValueError
        For a mode not in :data:`SHOOTING_MODES`, a segment count that is not an
        integer >= 1, or a ``max_segments`` that is not an integer >= ``segments``
        (:func:`~stickslip_fast.core.settings.check_integer`), naming the argument.
    """
    if shooting not in SHOOTING_MODES:
        raise ValueError(f"shooting must be one of {SHOOTING_MODES}, got {shooting!r}")
    if isinstance(segments, bool) or not isinstance(segments, (int, np.integer)) or segments < 1:
        raise ValueError(f"segments must be an integer >= 1, got {segments!r}")
    if max_segments is not None:
        check_integer("max_segments", max_segments, int(segments))


def _check_find_args(system, period, tol, rtol, atol, t_max, tangent_atol, max_iter) -> None:
    if not isinstance(system, System):
        raise TypeError(f"system must be a stickslip_fast.System, got {type(system).__name__}")
    if period is not None:
        if isinstance(period, bool) or not isinstance(period, (int, np.integer)) or period < 1:
            raise ValueError(f"period must be an integer >= 1, got {plain(period)}")
    for name, v in (
        ("tol", tol), ("rtol", rtol), ("atol", atol), ("t_max", t_max),
        ("tangent_atol", tangent_atol),
    ):  # fmt: skip
        if not (isinstance(v, (int, float, np.floating)) and math.isfinite(v) and v > 0):
            raise ValueError(f"{name} must be a finite number > 0, got {plain(v)}")
    if isinstance(max_iter, bool) or not isinstance(max_iter, (int, np.integer)) or max_iter < 0:
        raise ValueError(f"max_iter must be an integer >= 0, got {max_iter!r}")


def _find_single(system, z, period, *, tol, max_iter, rtol, atol, t_max, tangent_atol) -> Orbit:
    """Single shooting: damped Newton on P^p(z) - z from z (find_orbit's default)."""
    n = system.n_state
    mask = np.arange(n) != SECTION_INDEX
    z = z.copy()
    z[SECTION_INDEX] = 0.0
    kw = dict(rtol=rtol, atol=atol, t_max=t_max, tangent_atol=tangent_atol)

    def evaluate(zz):
        st, pts, times, jac = return_map(system, zz, period, **kw)
        if st != "ok":
            return st, pts, times, jac, np.inf
        return st, pts, times, jac, float(np.max(np.abs(pts[-1][mask] - zz[mask])))

    st, pts, times, jac, res = evaluate(z)
    history = [res]
    if st != "ok":
        return _orbit(system, period, z, pts, times, jac, res, 0, "integration-failed",
                      f"the return map failed at the start: {st}", history)  # fmt: skip
    it = 0
    rotated = False
    status, message = "max-iter", f"no convergence to tol={tol:g} in {max_iter} Newton steps"
    while True:
        if res <= tol:
            k = int(np.argmin(pts[:, 0]))
            if period > 1 and k != period - 1 and not rotated:
                # start again from the crossing with the smallest x1
                rotated = True
                z = pts[k].copy()
                z[SECTION_INDEX] = 0.0
                st, pts, times, jac, res = evaluate(z)
                history.append(res)
                if st == "ok" and res <= tol:
                    status, message = "converged", ""
                    break
                if st != "ok":
                    status, message = "integration-failed", f"the return map failed: {st}"
                    break
                continue
            status, message = "converged", ""
            break
        if it >= max_iter:
            break
        done, step = _newton_step(evaluate, z, pts, jac, res, mask)
        it += done != "singular"
        if done != "ok":
            status, message = step
            break
        z, pts, times, jac, res = step
        history.append(res)
    if status == "converged":
        status, message = _classify(system, z, pts, period, tol)
    return _orbit(system, period, z, pts, times, jac, res, it, status, message, history)


def _newton_step(evaluate, z, pts, jac, res, mask):
    """One damped Newton step: ("ok", (z, pts, times, jac, res)) or ("singular" | "stuck",
    (status, message)); a singular system takes no step, a stuck one counts as one."""
    n = z.size
    g = pts[-1][mask] - z[mask]
    try:
        dz = np.linalg.solve(jac - np.eye(n - 1), -g)
    except np.linalg.LinAlgError:
        return "singular", ("no-progress", "D P^p - I is singular (a multiplier at +1)")
    lam = 1.0
    for _ in range(21):
        z_new = z.copy()
        z_new[mask] += lam * dz
        st_n, pts_n, times_n, jac_n, res_n = evaluate(z_new)
        if st_n == "ok" and res_n < res:
            return "ok", (z_new, pts_n, times_n, jac_n, res_n)
        lam *= 0.5
    msg = f"no step along the Newton direction reduces the residual {res:.3g}"
    return "stuck", ("no-progress", msg)


def _classify(system, z, pts, period, tol):
    """(status, message) of a converged fixed point: an orbit, a rest point or a lower period."""
    # points in time order from z: z, then crossings 1..p-1
    q = _minimal_period(np.vstack([z, pts[:-1]]), tol)
    speed = float(np.max(np.abs(_field(system, z))))
    if speed < EQUILIBRIUM_SPEED:
        return (
            "equilibrium",
            f"converged onto a rest point (max |f| = {speed:.2g}): use find_equilibrium",
        )
    if q < period:
        return (
            "lower-period",
            f"converged onto an orbit of period {q}, a divisor of period={period}",
        )
    return "converged", ""


def _orbit(system, period, z, pts, times, jac, res, it, status, message, history) -> Orbit:
    n = system.n_state
    points = np.vstack([z[None, :], pts[:-1]]) if period > 1 else z[None, :].copy()
    if jac is None:
        jac = np.full((n - 1, n - 1), np.nan)
        mult = np.full(n - 1, np.nan, dtype=complex)
    else:
        mult = _multipliers(jac)
    converged = status == "converged"
    return Orbit(
        system=system,
        period=period,
        points=points,
        times=np.asarray(times, dtype=float),
        T=float(times[-1]),
        multipliers=mult,
        stable=bool(converged and multipliers_stable(system, mult)),
        jacobian=jac,
        residual=float(res),
        iterations=int(it),
        converged=converged,
        status=status,
        message=message,
        history=history,
    )
