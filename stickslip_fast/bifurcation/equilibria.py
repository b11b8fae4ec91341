"""Equilibria (steady sliding, a stalled motor) by Newton on f(y) = 0, with their eigenvalues."""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from ..base.messages import plain
from ..model.equations import dense_jacobian, friction, rest_position
from ..model.params import eta_prime
from ..model.system import System
from .returnmap import _field, _finite_state

#: A fixed point of the map where max |f| is below this is a rest point, not an orbit: near
#: a stable focus the return map contracts onto the equilibrium, which it leaves fixed.
EQUILIBRIUM_SPEED = 1e-8


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


# ------------------------------------------------------------- equilibria
def _sliding_guess(system: System, vb: float) -> np.ndarray:
    """dx = dphi = 0 at belt speed vb: the springs balance the sliding friction."""
    y = np.zeros(system.n_state)
    x, ph = rest_position(vb, system.to_array())
    if not (math.isfinite(x) and math.isfinite(ph)):  # |k12| = 1: no unique rest position
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


def _damped_newton(system: System, y: np.ndarray, tol: float, max_iter: int):
    """Newton on f(y) = 0, each step halved until ``max |f|`` decreases; (y, residual, steps)."""
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
    return y, res, it


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
    y, res, it = _damped_newton(system, y, tol, max_iter)
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
