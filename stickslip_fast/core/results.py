"""The record one run returns (:class:`SimulationResult`), below both the run and the file reader.

:func:`stickslip_fast.simulate` (analysis) builds it and
:func:`stickslip_fast.io.read_trajectory` (io) rebuilds it from a file, so it
lives here, under both.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..model.system import System
from .settings import Settings

__all__ = ["SimulationResult"]


@dataclass
class SimulationResult:
    """What :func:`simulate` returns.

    Attributes
    ----------
    system : System
    method : str
    state_names : list of str
        Column names of ``poincare``, ``y`` and ``final_state``.
    t_poincare : ndarray, shape (k,)
        Times of the recorded local minima of x1 (the last ``max_points``).
    poincare : ndarray, shape (k, n_state)
        Full state at those times. Empty unless status is "ok".
    n_crossings : int
        All crossings after t_transient (may exceed ``max_points``).
    period : int
        Smallest p <= 64 with which the points repeat; 0 if none, or if the points
        still drift towards rest (an oscillation dying out; docs/model.md "Period").
    status : str
        "ok", "equilibrium", "stalled", "unsettled", "no-crossings",
        "nonfinite", "step-underflow" or "max-steps" (see
        :data:`~stickslip_fast.STATUS_NAMES` and docs/reliability.md).
    n_steps, n_rejected : int
        Accepted and rejected steps.
    t_final : float
        Time reached: t_end, up to ``dwell`` later where the run's label was
        undecided at t_end (see :func:`simulate`'s ``equilibrium_tol`` and
        ``dwell``), earlier where it failed or converged.
    final_state : ndarray, shape (n_state,)
    amplitude : float
        Distance from rest over the recording window: the largest ``|dx_i|`` or
        ``|dphi_i|``, or the range of v_b (informative; the status is judged on
        the end of the run, see :func:`simulate`'s ``equilibrium_tol``).
    t_converged : float
        With ``stop="converged"``: when the run was found converged (NaN if it
        reached t_end first, and always with ``stop="fixed"``).
    rest_time : float
        How long the disks had been at rest at ``t_final`` (-1.0 if moving
        then): "equilibrium" needs ``dwell`` (or the whole recording window),
        less is "unsettled".
    t, y : ndarray or None
        Uniform samples from t_transient every ``sample_dt`` (when requested).
    settings : Settings
        The validated integration settings of the run.
    switching : dict or None
        With ``method="auto"``: ``to_stiff`` and ``to_explicit`` (switches each
        way), ``steps_explicit`` and ``steps_rosenbrock`` (accepted steps of each
        method), ``attempts_explicit`` and ``attempts_rosenbrock`` (attempted steps of
        each, accepted and rejected: they sum to ``n_steps + n_rejected``); None for the
        other methods.
    """

    system: System
    method: str
    state_names: list[str]
    t_poincare: np.ndarray
    poincare: np.ndarray
    n_crossings: int
    period: int
    status: str
    n_steps: int
    n_rejected: int
    t_final: float
    final_state: np.ndarray
    amplitude: float
    t_converged: float = float("nan")
    rest_time: float = -1.0
    t: np.ndarray | None = None
    y: np.ndarray | None = None
    settings: Settings | None = None
    switching: dict | None = None

    def column(self, name: str) -> np.ndarray:
        """Poincare coordinate ``name`` (e.g. "x1", "phi1") of every point."""
        return self.poincare[:, self.state_names.index(name)]

    def __repr__(self) -> str:
        return (
            f"SimulationResult(status={self.status!r}, period={self.period}, "
            f"points={len(self.t_poincare)}, n_steps={self.n_steps}, method={self.method!r})"
        )
