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

The tangents come from :func:`stickslip_fast.variational.propagate_tangents`
(the compiled Rodas5P with the exact variational Jacobian, the code the
Lyapunov exponent uses), integrated with n - 1 tangent vectors, the section's
coordinate directions.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from .interrupt import call_interruptible, new_abort_flag
from .messages import plain
from .model import dense_jacobian, friction, rhs
from .params import eta_prime
from .poincare import STATUS_NAMES
from .simulate import SimulationResult, simulate
from .system import SWEEPABLE, System
from .trajectory import kernel_variant
from .variational import propagate_sensitivity, propagate_tangents

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

#: Index of the section coordinate dx1 in the state.
SECTION_INDEX = 1
#: A fixed point of the map where max |f| is below this is a rest point, not an orbit: near
#: a stable focus the return map contracts onto the equilibrium, which it leaves fixed.
EQUILIBRIUM_SPEED = 1e-8

#: A disk sticks while its slip speed sqrt((dx - v_b)^2 + dphi^2) is below this many
#: eps (the friction law's regularisation; 100 eps = 1e-3 at the presets): far below
#: the slip speeds of a slip phase, far above the creep inside a stick phase.
STICK_SPEED = 100.0

#: Outcomes of :func:`find_orbit` (``Orbit.status``).
ORBIT_STATUSES = (
    "converged",  # residual <= tol: a fixed point of P^p
    "max-iter",  # max_iter Newton steps without reaching tol
    "no-progress",  # the damped step could not reduce the residual
    "lower-period",  # converged, but the points repeat with a divisor of the period asked for
    "equilibrium",  # converged onto a rest point (|f| ~ 0 there), not an orbit
    "integration-failed",  # the return map could not be evaluated at the start
)

_DEFAULT_RTOL = 1e-11
_DEFAULT_ATOL = 1e-13
_TANGENT_ATOL = 1e-10
_MAX_STEPS = 10_000_000


@dataclass
class Orbit:
    """A periodic orbit found by :func:`find_orbit`.

    Attributes
    ----------
    system : System
    period : int
        p: the number of section crossings per period.
    points : ndarray, shape (p, n_state)
        The states at the p crossings of the section (dx1 = 0 upward, the local
        minima of x1), in time order, starting at the one with the smallest x1.
    times : ndarray, shape (p,)
        Time from ``points[0]`` to each following crossing; ``times[-1]`` is T.
    T : float
        The period in time (NaN when the map could not be evaluated).
    multipliers : ndarray of complex, shape (n_state - 1,)
        Nontrivial Floquet multipliers: the eigenvalues of the return map's
        Jacobian in section coordinates, largest modulus first.
    stable : bool
        Converged and every multiplier inside the unit circle.
    jacobian : ndarray, shape (n_state - 1, n_state - 1)
        D P^p at ``points[0]`` in section coordinates (the state without dx1).
    residual : float
        ``max |P^p(z) - z|`` over the section coordinates at ``points[0]``.
    iterations : int
        Newton steps taken.
    converged : bool
        ``status == "converged"``.
    status : str
        One of :data:`ORBIT_STATUSES`.
    message : str
        What happened, in words (why it failed, for a failure).
    """

    system: System
    period: int
    points: np.ndarray
    times: np.ndarray
    T: float
    multipliers: np.ndarray
    stable: bool
    jacobian: np.ndarray
    residual: float
    iterations: int
    converged: bool
    status: str
    message: str = ""
    history: list[float] = field(default_factory=list, repr=False)

    @property
    def state_names(self) -> list[str]:
        """Column names of ``points``."""
        return self.system.state_names

    def __repr__(self) -> str:
        mult = ", ".join(f"{m:.4g}" for m in self.multipliers[:3])
        return (
            f"Orbit(status={self.status!r}, period={self.period}, T={self.T:.10g}, "
            f"residual={self.residual:.2e}, multipliers=[{mult}], stable={self.stable})"
        )


@dataclass
class Equilibrium:
    """An equilibrium found by :func:`find_equilibrium`.

    Attributes
    ----------
    system : System
    state : ndarray, shape (n_state,)
    eigenvalues : ndarray of complex
        Eigenvalues of the analytic Jacobian at ``state``, largest real part first.
    stable : bool
        Converged and every eigenvalue with a negative real part.
    kind : str
        "sliding" (constant belt, or a DC belt running above 1% of v_b0) or
        "stall" (a DC belt below 1% of v_b0).
    residual : float
        ``max |f(state)|``.
    iterations : int
    converged : bool
    """

    system: System
    state: np.ndarray
    eigenvalues: np.ndarray
    stable: bool
    kind: str
    residual: float
    iterations: int
    converged: bool


# ----------------------------------------------------------------- the map
def _finite_state(name: str, value: Any, n: int) -> np.ndarray:
    try:
        y = np.array(value, dtype=float)
    except (TypeError, ValueError) as exc:
        raise ValueError(f"{name} must be an array of {n} real numbers: {exc}") from None
    if y.shape != (n,):
        raise ValueError(f"{name} must have shape ({n},), got {y.shape}")
    if not np.all(np.isfinite(y)):
        raise ValueError(f"{name} must be finite, got {y}")
    return y


def _field(system: System, y: np.ndarray) -> np.ndarray:
    f = np.empty(y.size)
    rhs(y, system.to_array(), system.n_oscillators, system.is_dc_motor, f)
    return f


def return_map(
    system: System,
    z: np.ndarray,
    period: int = 1,
    *,
    rtol: float = _DEFAULT_RTOL,
    atol: float = _DEFAULT_ATOL,
    t_max: float = 1e4,
    tangents: bool = True,
    tangent_atol: float = _TANGENT_ATOL,
    param: str | None = None,
    param_step: float = 1e-7,
) -> tuple[str, np.ndarray, np.ndarray, np.ndarray | None]:
    """Evaluate P^p on the section and (optionally) its Jacobian.

    Parameters
    ----------
    system : System
    z : array_like, shape (n_state,)
        A point on the section; its dx1 entry is set to 0.
    period : int
        p, the number of crossings.
    rtol, atol : float
        Integration tolerances.
    t_max : float
        Longest time allowed from one crossing to the next.
    tangents : bool
        Also integrate the n - 1 tangent vectors and return the Jacobian.
    tangent_atol : float
        Error tolerance of a tangent vector relative to its length (1e-8
        leaves errors of ~1e-6 in the Jacobian at the presets; 1e-10 ~1e-9).
    param : str, optional
        A :class:`System` field (one of ``SWEEPABLE``): with ``tangents``, also
        integrate the sensitivity to it and return dP^p/d param as the
        Jacobian's last column.
    param_step : float
        Relative step h / max(1, |param|) of the central difference of the
        vector field and its Jacobian in ``param`` (one-sided at the edge of
        the parameter's valid range). It differences the model's equations, not
        the map, so no integration error is divided by h.

    Returns
    -------
    status : str
        "ok", or the driver's status of a failed segment ("no-crossings" when a
        segment reached ``t_max`` without a crossing).
    points : ndarray, shape (p, n_state)
        The states at crossings 1..p (``points[-1]`` = P^p(z)).
    times : ndarray, shape (p,)
        Times from z to each crossing.
    jacobian : ndarray, shape (n_state - 1, n_state - 1) or None
        D P^p(z) in section coordinates (None without ``tangents``); with
        ``param``, shape (n_state - 1, n_state): [D_z P^p, dP^p/d param].

    Raises
    ------
    ValueError
        For an unknown ``param``, or one that has no valid value on either side
        of its current one.
    """
    n = system.n_state
    mask = np.arange(n) != SECTION_INDEX
    p_arr = system.to_array()
    y = np.array(z, dtype=float)
    # a unit vector when no tangents are wanted: the tangent error norm is relative to |u|
    U = np.ascontiguousarray(np.eye(n)[:, mask] if tangents else np.eye(n)[:, :1])
    sens_p, sens_inv = _sensitivity_params(system, param if tangents else None, param_step)
    if sens_p is not None:
        U = np.ascontiguousarray(np.hstack([U, np.zeros((n, 1))]))
    variant = kernel_variant(system.n_oscillators, system.is_dc_motor)
    pts = np.full((period, n), np.nan)
    times = np.full(period, np.nan)
    t_acc = 0.0
    e = np.zeros(n)
    e[SECTION_INDEX] = 1.0
    for i in range(period):
        y[SECTION_INDEX] = 0.0  # exactly on the section: no crossing at t = 0
        args = (y, U, p_arr, system.n_oscillators, system.is_dc_motor, variant, float(t_max), 1,
                float(rtol), float(atol), float(tangent_atol))  # fmt: skip
        if sens_p is None:
            code, y1, U1, t = call_interruptible(
                propagate_tangents, *args, _MAX_STEPS, abort=new_abort_flag()
            )
        else:
            code, y1, U1, t = call_interruptible(
                propagate_sensitivity, *args, sens_p, sens_inv, _MAX_STEPS, abort=new_abort_flag()
            )  # fmt: skip
        status = STATUS_NAMES[code]
        if status == "ok" and not math.isfinite(t):
            status = "no-crossings"
        if status != "ok" or not np.all(np.isfinite(y1)):
            return (status if status != "ok" else "nonfinite"), pts, times, None
        t_acc += t
        pts[i] = y1
        times[i] = t_acc
        if tangents:
            f = _field(system, y1)
            # projection along the flow onto the section (see the module docstring)
            U = np.ascontiguousarray(U1 - np.outer(f, U1[SECTION_INDEX] / f[SECTION_INDEX]))
        y = np.ascontiguousarray(y1)
    jac = U[mask] if tangents else None
    return "ok", pts, times, jac


def _sensitivity_params(system: System, param: str | None, rel_step: float):
    """(p2, inv) of :func:`propagate_sensitivity` for the sensitivity to ``param``.

    Rows: the packed parameters at param + h and param - h, or at param and one
    of them where the other is outside the parameter's valid range. (None, 0.0)
    without ``param``.
    """
    if param is None:
        return None, 0.0
    if param not in SWEEPABLE:
        raise ValueError(f"param must be one of {sorted(SWEEPABLE)}, got {param!r}")
    if not (isinstance(rel_step, (int, float)) and 0 < rel_step < 1e-2):
        raise ValueError(f"param_step must be a number in (0, 0.01), got {plain(rel_step)}")
    lam = float(getattr(system, param))
    h = rel_step * max(1.0, abs(lam))

    def at(v):
        try:
            return system.replace(**{param: v}).to_array(), v
        except ValueError:  # outside the parameter's valid range
            return None

    hi, lo = at(lam + h), at(lam - h)
    if hi is None and lo is None:
        raise ValueError(f"{param} = {lam} has no valid value within {h:g} on either side")
    hi = hi or (system.to_array(), lam)
    lo = lo or (system.to_array(), lam)
    return np.ascontiguousarray(np.stack([hi[0], lo[0]])), 1.0 / (hi[1] - lo[1])


def _multipliers(jac: np.ndarray) -> np.ndarray:
    ev = np.linalg.eigvals(jac).astype(complex)
    return ev[np.argsort(-np.abs(ev), kind="stable")]


def _minimal_period(points: np.ndarray, tol: float) -> int:
    p = points.shape[0]
    scale = max(1.0, float(np.max(np.abs(points))))
    for q in range(1, p):
        if p % q == 0 and np.max(np.abs(points[q:] - points[:-q])) <= 100 * tol * scale:
            return q
    return p


# ------------------------------------------------------------------ orbits
def _start_from(system: System, start: Any, period: int | None, t_max: float):
    """(z on the section, period) from a state, a SimulationResult or a census Attractor."""
    from .census import Attractor

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


def find_orbit(
    system: System,
    start: Any,
    period: int | None = None,
    *,
    tol: float = 1e-10,
    max_iter: int = 30,
    rtol: float = _DEFAULT_RTOL,
    atol: float = _DEFAULT_ATOL,
    t_max: float = 1e4,
    tangent_atol: float = _TANGENT_ATOL,
) -> Orbit:
    """Find a periodic orbit by damped Newton on P^p(z) - z over the section.

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
    max_iter : int
        Most Newton steps.
    rtol, atol : float
        Tolerances of the variational integration (tighter than the simulation
        defaults: the residual cannot go below the map's integration noise).
    t_max : float
        Longest time allowed between two crossings.
    tangent_atol : float
        Tolerance of the tangent vectors relative to their length (see
        :func:`return_map`).

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
    if not isinstance(system, System):
        raise TypeError(f"system must be a stickslip_fast.System, got {type(system).__name__}")
    if period is not None:
        if isinstance(period, bool) or not isinstance(period, (int, np.integer)) or period < 1:
            raise ValueError(f"period must be an integer >= 1, got {plain(period)}")
        period = int(period)
    for name, v in (
        ("tol", tol), ("rtol", rtol), ("atol", atol), ("t_max", t_max),
        ("tangent_atol", tangent_atol),
    ):  # fmt: skip
        if not (isinstance(v, (int, float, np.floating)) and math.isfinite(v) and v > 0):
            raise ValueError(f"{name} must be a finite number > 0, got {plain(v)}")
    if isinstance(max_iter, bool) or not isinstance(max_iter, (int, np.integer)) or max_iter < 0:
        raise ValueError(f"max_iter must be an integer >= 0, got {max_iter!r}")
    z, period = _start_from(system, start, period, t_max)
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
        g = pts[-1][mask] - z[mask]
        try:
            dz = np.linalg.solve(jac - np.eye(n - 1), -g)
        except np.linalg.LinAlgError:
            status, message = "no-progress", "D P^p - I is singular (a multiplier at +1)"
            break
        it += 1
        lam = 1.0
        for _ in range(21):
            z_new = z.copy()
            z_new[mask] += lam * dz
            st_n, pts_n, times_n, jac_n, res_n = evaluate(z_new)
            if st_n == "ok" and res_n < res:
                break
            lam *= 0.5
        else:
            status = "no-progress"
            message = f"no step along the Newton direction reduces the residual {res:.3g}"
            break
        z, pts, times, jac, res = z_new, pts_n, times_n, jac_n, res_n
        history.append(res)
    if status == "converged":
        # points in time order from z: z, then crossings 1..p-1
        q = _minimal_period(np.vstack([z, pts[:-1]]), tol)
        speed = float(np.max(np.abs(_field(system, z))))
        if speed < EQUILIBRIUM_SPEED:
            status = "equilibrium"
            message = f"converged onto a rest point (max |f| = {speed:.2g}): use find_equilibrium"
        elif q < period:
            status = "lower-period"
            message = f"converged onto an orbit of period {q}, a divisor of period={period}"
    return _orbit(system, period, z, pts, times, jac, res, it, status, message, history)


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
        stable=bool(converged and np.all(np.abs(mult) < 1.0)),
        jacobian=jac,
        residual=float(res),
        iterations=int(it),
        converged=converged,
        status=status,
        message=message,
        history=history,
    )


# ------------------------------------------------------------- equilibria
def _sliding_guess(system: System, vb: float) -> np.ndarray:
    """dx = dphi = 0 at belt speed vb: the springs balance the sliding friction."""
    n = system.n_state
    y = np.zeros(n)
    ts, ms = friction(-vb, 0.0, system.eps, eta_prime(system.eta))
    a = np.array([[1.0, system.k12], [system.k12, 1.0]])
    rhs_ = -system.mu * np.array([ts, ms])
    try:
        x, ph = np.linalg.solve(a, rhs_)
    except np.linalg.LinAlgError:
        x, ph = 0.0, 0.0
    for i in range(system.n_oscillators):
        y[4 * i] = x
        y[4 * i + 2] = ph
    if system.is_dc_motor:
        y[-1] = vb
    return y


def _belt_speed(system: System, which: str) -> float:
    """The belt speed of a rest point: v_b (constant belt), or a root of the motor equation.

    At rest every disk has slip velocity -v_b, so the DC motor's equation reads
    g(v) = v_b0 + beta T_s(-v, 0) - v = 0. Its roots are bracketed on a log grid
    from 1e-4 eps to 2 v_b0: the largest is steady sliding, the smallest (inside
    the stick band, when the load is strong enough) the stall.
    """
    if not system.is_dc_motor:
        return system.vb
    etap = eta_prime(system.eta)

    def g(v: float) -> float:
        return system.vb0 + system.beta * friction(-v, 0.0, system.eps, etap)[0] - v

    grid = np.geomspace(1e-4 * system.eps, 2.0 * max(system.vb0, system.eps), 2000)
    vals = np.array([g(v) for v in grid])
    roots = []
    for i in np.nonzero(np.sign(vals[:-1]) != np.sign(vals[1:]))[0]:
        a, b = grid[i], grid[i + 1]
        for _ in range(200):  # bisection
            mid = 0.5 * (a + b)
            if np.sign(g(mid)) == np.sign(g(a)):
                a = mid
            else:
                b = mid
            if b - a <= 1e-15 * b:
                break
        roots.append(0.5 * (a + b))
    if which == "sliding":
        return roots[-1] if roots else system.vb0
    # no root below 1% of v_b0: no stall; Newton from v_b = eps then reports converged=False
    # rather than returning the sliding state for a stall
    return roots[0] if roots and roots[0] < 0.01 * system.vb0 else system.eps


def find_equilibrium(
    system: System,
    start: Any = "sliding",
    *,
    tol: float = 1e-12,
    max_iter: int = 50,
) -> Equilibrium:
    """Find an equilibrium (steady sliding, or the stalled DC motor) by Newton on f(y) = 0.

    Parameters
    ----------
    system : System
    start : {"sliding", "stall"} or array_like
        ``"sliding"``: the disks at rest on a belt running at v_b (constant
        drive) or at the largest root of the motor equation (DC motor; see
        :func:`_belt_speed`). ``"stall"`` (DC motor only): the smallest root,
        the belt nearly stopped inside the friction law's stick band (it exists
        when beta times the friction peak exceeds about v_b0). The springs then
        balance the sliding friction. Or a state to start Newton from.
    tol : float
        Convergence: ``max |f(y)|`` <= tol.
    max_iter : int
        Most Newton steps (each halved until ``|f|`` decreases).

    Returns
    -------
    Equilibrium

    Raises
    ------
    ValueError
        For an unknown start, a non-finite start state, or ``"stall"`` with a
        constant belt.
    """
    if not isinstance(system, System):
        raise TypeError(f"system must be a stickslip_fast.System, got {type(system).__name__}")
    if isinstance(start, str):
        if start not in ("sliding", "stall"):
            raise ValueError(f'start must be "sliding", "stall" or a state, got {plain(start)}')
        if start == "stall" and not system.is_dc_motor:
            raise ValueError('start="stall" needs a DC-motor drive (drive="dc-motor")')
        y = _sliding_guess(system, _belt_speed(system, start))
    else:
        y = _finite_state("start", start, system.n_state)
    if not (isinstance(tol, (int, float)) and math.isfinite(tol) and tol > 0):
        raise ValueError(f"tol must be a finite number > 0, got {plain(tol)}")
    p = system.to_array()
    nosc, dc = system.n_oscillators, system.is_dc_motor
    f = _field(system, y)
    res = float(np.max(np.abs(f)))
    it = 0
    while res > tol and it < max_iter:
        jac = dense_jacobian(y, p, nosc, dc)
        try:
            dy = np.linalg.solve(jac, -f)
        except np.linalg.LinAlgError:
            break
        it += 1
        lam = 1.0
        for _ in range(30):
            y_new = y + lam * dy
            f_new = _field(system, y_new)
            r_new = float(np.max(np.abs(f_new)))
            if np.isfinite(r_new) and r_new < res:
                break
            lam *= 0.5
        else:
            break
        y, f, res = y_new, f_new, r_new
    converged = res <= tol
    ev = np.linalg.eigvals(dense_jacobian(y, p, nosc, dc)).astype(complex)
    ev = ev[np.argsort(-ev.real, kind="stable")]
    kind = "stall" if dc and abs(y[-1]) < 0.01 * abs(system.vb0) else "sliding"
    return Equilibrium(
        system=system,
        state=y,
        eigenvalues=ev,
        stable=bool(converged and np.all(ev.real < 0)),
        kind=kind,
        residual=res,
        iterations=it,
        converged=converged,
    )


def stick_phases(
    system: System,
    point: np.ndarray,
    T: float,
    *,
    threshold: float = STICK_SPEED,
    n_samples: int = 20000,
    rtol: float = 1e-10,
    atol: float = 1e-12,
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
    dt = T / n_samples
    r = simulate(system, T, y0=y0, sample_dt=dt, rtol=rtol, atol=atol, max_points=1)
    y = r.y[:n_samples]
    if y.shape[0] < n_samples or not np.all(np.isfinite(y)):
        raise ValueError(f"the orbit could not be sampled over one period (status {r.status!r})")
    n = system.n_oscillators
    vb = y[:, -1] if system.is_dc_motor else np.full(len(y), system.vb)
    out = []
    for i in range(n):
        speed = np.hypot(y[:, 4 * i + 1] - vb, y[:, 4 * i + 3])
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
