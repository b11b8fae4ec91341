"""The p-th return map on the Poincare section, its Jacobian and parameter derivative.

The formula of the Jacobian and of the parameter derivative: :mod:`.orbits` and
docs/orbits.md. The tangents come from :func:`stickslip_fast.core.variational.propagate_tangents`."""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from ..base.interrupt import new_abort_flag
from ..base.journal import call_journaled
from ..base.messages import plain
from ..core.poincare import STATUS_NAMES
from ..core.trajectory import kernel_variant
from ..core.variational import propagate_sensitivity, propagate_tangents
from ..model.equations import rhs
from ..model.system import SWEEPABLE, System

#: Index of the section coordinate dx1 in the state.
SECTION_INDEX = 1


_DEFAULT_RTOL = 1e-11


_DEFAULT_ATOL = 1e-13


_TANGENT_ATOL = 1e-10


_MAX_STEPS = 10_000_000


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
        Relative step h / max(1, |param|) (``vb``, ``eps``: h / (10 eps)) of the
        central difference of the vector field and its Jacobian in ``param``
        (one-sided at the edge of the parameter's valid range). It differences
        the model's equations, not the map: no integration error is divided by h.

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
    y = np.array(z, dtype=float)
    sens = _sensitivity_params(system, param if tangents else None, param_step)
    U = _initial_tangents(n, mask, tangents, sens[0] is not None)
    integrate = _crossing_integrator(system, sens, t_max, rtol, atol, tangent_atol)
    pts = np.full((period, n), np.nan)
    times = np.full(period, np.nan)
    t_acc = 0.0
    for i in range(period):
        status, y1, U1, t = integrate(y, U)
        if status != "ok":
            return status, pts, times, None
        t_acc += t
        pts[i] = y1
        times[i] = t_acc
        if tangents:
            U = _project_on_section(system, y1, U1)
        y = np.ascontiguousarray(y1)
    return "ok", pts, times, (U[mask] if tangents else None)


def _initial_tangents(n: int, mask: np.ndarray, tangents: bool, sensitivity: bool) -> np.ndarray:
    """The tangent vectors at the start: the section's coordinate directions (a unit vector
    when no tangents are wanted: the tangent error norm is relative to |u|), and a zero
    column for the parameter sensitivity."""
    U = np.ascontiguousarray(np.eye(n)[:, mask] if tangents else np.eye(n)[:, :1])
    if sensitivity:
        U = np.ascontiguousarray(np.hstack([U, np.zeros((n, 1))]))
    return U


def _crossing_integrator(
    system: System,
    sens: tuple[np.ndarray | None, float],
    t_max: float,
    rtol: float,
    atol: float,
    tangent_atol: float,
):
    """``integrate(y, U) -> (status, y1, U1, t)``: from y, put on the section (its dx1
    entry set to 0, in place), to the next upward crossing, with the tangents U (and the
    sensitivity, with ``sens``).

    ``status`` is "ok", the driver's status of a failed run, "no-crossings" (``t_max``
    reached) or "nonfinite" (a state that is not finite)."""
    p_arr = system.to_array()
    variant = kernel_variant(system.n_oscillators, system.is_dc_motor)
    sens_p, sens_inv = sens

    def integrate(y: np.ndarray, U: np.ndarray):
        y[SECTION_INDEX] = 0.0  # exactly on the section: no crossing at t = 0
        args = (y, U, p_arr, system.n_oscillators, system.is_dc_motor, variant, float(t_max), 1,
                float(rtol), float(atol), float(tangent_atol))  # fmt: skip
        if sens_p is None:
            code, y1, U1, t = call_journaled(
                propagate_tangents, *args, _MAX_STEPS, abort=new_abort_flag()
            )
        else:
            code, y1, U1, t = call_journaled(
                propagate_sensitivity, *args, sens_p, sens_inv, _MAX_STEPS, abort=new_abort_flag()
            )  # fmt: skip
        status = STATUS_NAMES[code]
        if status == "ok" and not math.isfinite(t):
            status = "no-crossings"
        if status == "ok" and not np.all(np.isfinite(y1)):
            status = "nonfinite"
        return status, y1, U1, t

    return integrate


def _project_on_section(system: System, y1: np.ndarray, U1: np.ndarray) -> np.ndarray:
    """The tangents U1 at the crossing y1 projected along the flow onto the section (see
    :mod:`.orbits`): their dx1 rows become 0."""
    f = _field(system, y1)
    return np.ascontiguousarray(U1 - np.outer(f, U1[SECTION_INDEX] / f[SECTION_INDEX]))


#: The belt speed and eps act through the friction law's slip speed, where the law varies
#: on scales far below eps (the creep of a stick phase): there the step is param_step x
#: this x eps. With h = 1e-7 (1 % of eps, the old step) dP/dv_b came out with the wrong
#: sign at eta = 2 (0.276 by differences of the map, -0.298), and dP/deps 5 % off.
FRICTION_SCALE = 10.0


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
    h = rel_step * (FRICTION_SCALE * system.eps if param in ("vb", "eps") else max(1.0, abs(lam)))
    h = max(h, 1e-10 * abs(lam))  # not below round-off in lambda, whatever eps

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
