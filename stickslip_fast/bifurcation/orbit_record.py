"""The :class:`Orbit` record of :func:`~stickslip_fast.bifurcation.orbits.find_orbit`."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ..model.system import System
from .detection import RANK_GAP_MIN

#: Outcomes of :func:`find_orbit` (``Orbit.status``).
ORBIT_STATUSES = (
    "converged",  # residual <= tol: a fixed point of P^p
    "max-iter",  # max_iter Newton steps without reaching tol
    "no-progress",  # the damped step could not reduce the residual
    "lower-period",  # converged, but the points repeat with a divisor of the period asked for
    "equilibrium",  # converged onto a rest point (|f| ~ 0 there), not an orbit
    "integration-failed",  # the return map could not be evaluated at the start
)


def branch_point_marks(system) -> dict[str, Any]:
    """:func:`~stickslip_fast.bifurcation.arclength.pseudo_arclength`'s ``branch_points``
    and ``noise_gap`` for an orbit branch of ``system``: look for branch points, and read
    no label where DG has a second null direction to within its noise
    (:data:`.detection.RANK_GAP_MIN`). Neither for N >= 2 disks on a constant belt,
    whose uncoupled disks keep their phases (N - 1 multipliers are exactly 1, so DG is
    singular all along every branch, and its folds were always read so)."""
    on = bool(system.is_dc_motor or system.n_oscillators == 1)
    return {"branch_points": on, "noise_gap": RANK_GAP_MIN if on else 0.0}


def multipliers_stable(system: System, multipliers: np.ndarray) -> np.ndarray | bool:
    """Whether orbits with these multipliers (shape (..., n_state - 1)) are stable.

    Every multiplier inside the unit circle, except for N >= 2 disks on a constant
    belt: uncoupled disks each keep their own phase, so N - 1 multipliers are exactly
    1 (a shift of one disk along its orbit is another periodic orbit) and the orbit
    is never asymptotically stable, however the rounding places them (1 - ~1e-6).
    """
    inside = np.all(np.abs(multipliers) < 1.0, axis=-1)
    if system.n_oscillators >= 2 and not system.is_dc_motor:
        inside = np.zeros_like(inside)
    return inside


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
        Jacobian in section coordinates, largest modulus first. Those below ~1e-8
        are the Jacobian's rounding, not values: a stick phase crushes the
        directions it locks far below the float range (at eta = 2.0 to about
        e^-24 800 and e^-62 000; :func:`~stickslip_fast.lyapunov_spectrum` resolves
        them as exponents, docs/lyapunov.md).
    stable : bool
        Converged and every multiplier inside the unit circle. Never True for
        N >= 2 disks on a constant belt: they are uncoupled, so N - 1 multipliers
        are exactly 1 (each disk's phase is free; computed as 1 - ~1e-6), and the
        orbit is neutrally, not asymptotically, stable (:func:`multipliers_stable`).
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
    segments : tuple of (ndarray, ndarray) or None
        Multiple shooting only: ``(mesh, starts)``, the mesh as fractions of T
        (shape (m + 1,), from 0 to 1) and the segments' start states (shape
        (m, n_state); ``starts[0]`` is ``points[0]``). ``continue_orbit`` starts
        from them: past a multiplier of ~1e8 one trajectory from ``points[0]`` does
        not stay near the orbit for a whole period. None for single shooting.
    origin : Bifurcation or None
        The bifurcation :func:`~stickslip_fast.switch_branch` found this orbit from, on
        a branch in the parameter ``origin_param`` (None and "" otherwise).
        :func:`~stickslip_fast.continue_orbit` in that parameter reads it for its
        defaults: it walks away from ``origin.value`` and, from a branch point, takes a
        first step of ``walk_args.BRANCH_POINT_DS``.
    origin_param : str
        The parameter of the branch ``origin`` lies on.
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
    segments: tuple[np.ndarray, np.ndarray] | None = field(default=None, repr=False)
    origin: Any = field(default=None, repr=False)  # a Bifurcation (branch.py imports this module)
    origin_param: str = field(default="", repr=False)

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
