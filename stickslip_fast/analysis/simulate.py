"""Public single-trajectory API: :func:`simulate`."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..base.docs import fill_doc
from ..base.interrupt import call_interruptible, new_abort_flag
from ..core.autoswitch import AUTO_STATS
from ..core.poincare import MAX_PERIOD, STATUS_NAMES, orbit_period
from ..core.results import SimulationResult
from ..core.settings import (
    DEFAULT_ATOL,
    DEFAULT_EQUILIBRIUM_TOL,
    DEFAULT_MAX_STEPS,
    DEFAULT_RTOL,
    Settings,
    check_memory,
    check_real,
    period_tolerance,
    system_defaults,
    warn_if_coarse_atol,
)
from ..core.trajectory import (
    F_AMPLITUDE,
    F_REST_TIME,
    F_T_CONVERGED,
    F_T_FINAL,
    I_CROSSINGS,
    I_REJECTED,
    I_SAMPLES,
    I_STEPS,
    I_TO_STIFF,
    METHODS,
    N_STAT_F,
    N_STAT_I,
    integrate,
    method_variant,
)
from ..model.system import System, warn_if_synchronous

__all__ = [
    "simulate",
    "SimulationResult",
    "DEFAULT_RTOL",
    "DEFAULT_ATOL",
    "DEFAULT_EQUILIBRIUM_TOL",
    "DEFAULT_MAX_STEPS",
    "MAX_PERIOD",
    "period_tolerance",
]

#: State-sized work arrays of one compiled run (stages, error estimate, dense
#: output, Jacobian blocks), an upper bound for the memory estimate.
WORKSPACE_VECTORS = 64


#: The ``method``, ``rtol``, ``atol`` and ``h`` entries of the docstrings (numpydoc).
METHOD_PARAMS_DOC = """
    method : {"rodas5p", "dopri5", "dopri5-fixed", "rodas4p", "rodas4p2", "auto"}
        ``"rodas5p"`` (default): L-stable Rosenbrock-Wanner, order 5(4), for the
        stiff sticking phases. ``"dopri5"``: adaptive Dormand-Prince 5(4) with PI
        control. ``"dopri5-fixed"``: Dormand-Prince with the fixed step ``h``.
        ``"rodas4p"``, ``"rodas4p2"``: 6-stage Rosenbrock-Wanner 4(3) methods;
        cheaper per step but slower than ``"rodas5p"`` at every accuracy
        measured (docs/model.md). ``"auto"``: Dormand-Prince while the motion is
        non-stiff, Rodas5P while it is stiff (a disk sticks, or near a
        stick-slip switch), switched by stiffness estimates; the switches and
        each method's steps are in ``result.switching`` (docs/performance.md,
        "Stiffness-aware switching").
    rtol, atol : float, optional
        Tolerances of the adaptive methods (rtol at most 1e-2). Defaults: rtol 1e-9;
        atol 1e-11, and 1e-6 eps where the friction law's eps (its smallest, with a
        swept eps) is below 1e-5 (:func:`~stickslip_fast.core.settings.default_atol`).
    h : float, optional
        Fixed step size. Required by ``"dopri5-fixed"``; with ``"rodas5p"`` it
        runs the Rosenbrock method with fixed steps (for convergence studies)."""

#: The ``max_steps``, ``equilibrium_tol``, ``period_tol``, ``stop`` and ``dwell`` entries.
CLASSIFY_PARAMS_DOC = """
    max_steps : int, optional
        Give up with status "max-steps" after this many accepted steps.
    equilibrium_tol : float
        The run counts as at rest ("equilibrium", or "stalled" when a DC motor's
        belt is below 1% of v_b0) when, over its last ``dwell`` time units (or
        the whole recording window if that is shorter), no disk velocity
        exceeds this and the belt speed varies by less. A run at rest (or with
        disk 1 at rest) at ``t_end`` for less than that goes on, for at most
        ``dwell``, until disk 1 moves or the rest has lasted that long (so
        ``t_final`` may exceed ``t_end``); one still at rest for less is
        "unsettled" (never an orbit: its crossings would be round-off minima of
        x1 at rest). Motion that died out earlier
        never counts. Default 1e-4, ten times the presets' eps (inside the
        friction law's stick band a "stuck" disk creeps at O(eps)), and 1e-2 of
        the belt speed (v_b, or v_b0 on a DC motor; the slowest of a sweep) where
        that is smaller: a sticking disk rides with the belt
        (:func:`~stickslip_fast.core.settings.default_equilibrium_tol`).
    period_tol : float, optional
        Relative tolerance of the period detector (default 1e4 rtol, at most 1e-4:
        :func:`period_tolerance`).
    stop : {"fixed", "converged"}
        ``"fixed"`` (default): run to ``t_end`` and record after ``t_transient``.
        ``"converged"``: watch the run from t = 0 (``t_transient`` is not used)
        and end it once it has converged: the Poincare points repeat with a
        period p <= 64 to ``period_tol`` over at least 3 periods and 8 points
        and have stopped drifting (their change still to come, extrapolated
        geometrically, is within ``period_tol`` too), or the disks have been at
        rest (speeds, and the belt-speed range, below ``equilibrium_tol``) for
        ``dwell``. An orbit then records max(8, 4 p) more points (at most
        ``max_points``), which are the ones returned, and ends where disk 1
        moves. ``t_end`` is the cap; ``t_converged`` is NaN when it was reached
        first, or when the points would converge too late to be recorded before
        it (such a run is judged at ``t_end`` like a fixed window).
    dwell : float, optional
        Time at rest at the end of the run that makes it an equilibrium (see
        ``equilibrium_tol``); with ``stop="converged"`` also the time at rest
        after which the run ends (default 200, about 15 periods of the slowest
        free oscillation, and 200 x 0.0112 / v_b for a belt slower than the
        presets' v_b = 0.0112, whose stick phases last longer in proportion:
        :func:`~stickslip_fast.core.settings.default_dwell`). An orbit needs a
        crossing within the last ``dwell``; a run whose disk 1 moves and that
        crossed before waits up to ``dwell`` past ``t_end`` for its next
        crossing."""


@fill_doc(method_params=METHOD_PARAMS_DOC, classify_params=CLASSIFY_PARAMS_DOC)
def simulate(
    system: System,
    t_end: float,
    t_transient: float = 0.0,
    y0=None,
    method: str = "rodas5p",
    rtol: float | None = None,
    atol: float | None = None,
    h: float | None = None,
    max_points: int = 1000,
    sample_dt: float | None = None,
    *,
    max_steps: int | None = None,
    equilibrium_tol: float | None = None,
    period_tol: float | None = None,
    stop: str = "fixed",
    dwell: float | None = None,
) -> SimulationResult:
    """Integrate one trajectory and record its Poincare points.

    Parameters
    ----------
    system : System
    t_end : float
        Final time (nondimensional).
    t_transient : float
        Points, samples and ``amplitude`` are taken only for t >= t_transient.
        The classification does not depend on it being long enough: it reads
        the end of the run (see ``equilibrium_tol``), so the default 0 gives
        correct labels, but with it the returned points include the transient.
    y0 : array_like, optional
        Initial state in ``system.state_names`` order; default zeros
        (v_b(0) = 0 for the DC motor, as in the paper). With N >= 2 disks on a
        DC motor the default puts every disk in one state, where they stay: a
        :class:`~stickslip_fast.SynchronousStartWarning` says so (the paper's Figs. 14-18
        displace disk 2).
    {method_params}
    max_points : int
        Keep at most this many points: the most recent ones. 0 records none
        (only the status and final state; the period is then 0, undetected).
    sample_dt : float, optional
        Also return ``t`` and ``y`` on a uniform grid t_transient + k sample_dt.
    {classify_params}

    Returns
    -------
    SimulationResult

    Examples
    --------
    >>> import stickslip_fast as ssf
    >>> res = ssf.simulate(ssf.System.preset("asymmetric", eta=9.99), 3000, 2000)
    >>> res.status, res.period  # doctest: +SKIP
    ('ok', 2)
    """
    if not isinstance(system, System):
        raise TypeError(f"system must be a stickslip_fast.System, got {type(system).__name__}")
    atol, equilibrium_tol, dwell = system_defaults(
        system, atol=atol, equilibrium_tol=equilibrium_tol, dwell=dwell
    )
    s = Settings.resolve(
        method, t_end, t_transient, rtol, atol, h, max_points, max_steps, equilibrium_tol,
        period_tol, stop=stop, dwell=dwell,
    )  # fmt: skip
    y_init = system.initial_state(y0)
    if y0 is None:
        warn_if_synchronous(system, "the default start y0 (rest)", stacklevel=2)
    warn_if_coarse_atol(system.eps, s.atol, stacklevel=2)
    if sample_dt is not None:
        sample_dt = check_real("sample_dt", sample_dt)
    bufs = _RunBuffers.allocate(system, s, sample_dt)
    code = _run_kernel(system, s, y_init, sample_dt, bufs)
    return _result(system, s, STATUS_NAMES[code], sample_dt, bufs)


@dataclass
class _RunBuffers:
    """The arrays one compiled run writes into (allocated once, before the run)."""

    ring: np.ndarray
    tring: np.ndarray
    samples: np.ndarray
    stat_i: np.ndarray
    stat_f: np.ndarray
    y_end: np.ndarray

    @classmethod
    def allocate(cls, system: System, s: Settings, sample_dt: float | None) -> _RunBuffers:
        n = system.n_state
        if sample_dt is not None:
            n_samples = int(math.floor((s.t_end - s.t_transient) / sample_dt + 1e-9)) + 1
        else:
            n_samples = 0
        check_memory(
            8 * n * (s.max_points + n_samples + WORKSPACE_VECTORS) + 8 * s.max_points,
            f"a run with n_oscillators = {system.n_oscillators}, max_points = {s.max_points}"
            + (
                "" if sample_dt is None else f" and {n_samples} samples (sample_dt = {sample_dt:g})"
            ),
        )
        return cls(
            ring=np.empty((s.max_points, n)),
            tring=np.empty(s.max_points),
            samples=np.empty((n_samples, n)),
            stat_i=np.zeros(N_STAT_I, dtype=np.int64),
            stat_f=np.zeros(N_STAT_F),
            y_end=np.empty(n),
        )


def _run_kernel(
    system: System, s: Settings, y_init: np.ndarray, sample_dt: float | None, b: _RunBuffers
) -> int:
    """Run the compiled trajectory kernel (interruptible); its status code."""
    rs = s.run_settings()
    method = METHODS.index(s.method)
    n_osc, dc = system.n_oscillators, system.is_dc_motor
    return call_interruptible(
        integrate, method, y_init, system.to_array(), n_osc, dc,
        method_variant(method, n_osc, dc), rs, b.ring,
        b.tring, b.samples, 1.0 if sample_dt is None else sample_dt,
        b.y_end, b.stat_i, b.stat_f, abort=new_abort_flag(),
    )  # fmt: skip


def _ring_points(b: _RunBuffers, n_cross: int, max_points: int) -> tuple:
    """(times, states) of the last ``max_points`` recorded crossings, in time order."""
    # trajectory.unroll_ring in NumPy: Python calling the compiled one would compile
    # its entry twin in every first run (base.jit)
    cap = b.ring.shape[0]
    k = min(n_cross, max_points, cap)
    slots = (n_cross - k + np.arange(k)) % cap
    return b.tring[slots], b.ring[slots]


def recorded_crossings(
    system: System, t_end: float, y0=None, *, rtol: float | None = None,
    atol: float | None = None, max_points: int = 4096,
) -> tuple[np.ndarray, np.ndarray, str]:  # fmt: skip
    """The Poincare points of one run from t = 0, whatever its status.

    :func:`simulate` returns points only for status ``"ok"``: those of a run that
    comes to rest are its transient, not an attractor's. Edge tracking needs
    exactly that transient (how long a start near a basin boundary shadows a
    saddle before it settles), so this returns the last ``max_points`` recorded
    crossings (times, states) with the status, under ``simulate``'s default
    settings otherwise (Rodas5P, fixed stopping).
    """
    atol, equilibrium_tol, dwell = system_defaults(system, atol=atol)
    s = Settings.resolve(
        "rodas5p", t_end, 0.0, rtol, atol, None, max_points, None, equilibrium_tol, None,
        dwell=dwell,
    )  # fmt: skip
    bufs = _RunBuffers.allocate(system, s, None)
    code = _run_kernel(system, s, system.initial_state(y0), None, bufs)
    tp, pts = _ring_points(bufs, int(bufs.stat_i[I_CROSSINGS]), s.max_points)
    return tp, pts, STATUS_NAMES[code]


def _result(
    system: System, s: Settings, status: str, sample_dt: float | None, b: _RunBuffers
) -> SimulationResult:
    """The run's points in time order, its period, samples and statistics."""
    n = system.n_state
    stat_i, stat_f = b.stat_i, b.stat_f
    n_cross = int(stat_i[I_CROSSINGS])
    period = 0
    if status == "ok":
        tp, pts = _ring_points(b, n_cross, s.max_points)
        period = int(
            orbit_period(
                pts, len(tp), s.period_tol, MAX_PERIOD, system.to_array(),
                system.n_oscillators, system.is_dc_motor,
            )
        )  # fmt: skip
    else:
        tp, pts = np.empty(0), np.empty((0, n))
    t = y = None
    if sample_dt is not None:
        m = int(stat_i[I_SAMPLES])
        t = s.t_transient + sample_dt * np.arange(m)
        y = b.samples[:m]
    return SimulationResult(
        system=system,
        method=s.method,
        state_names=system.state_names,
        t_poincare=tp,
        poincare=pts,
        n_crossings=n_cross,
        period=period,
        status=status,
        n_steps=int(stat_i[I_STEPS]),
        n_rejected=int(stat_i[I_REJECTED]),
        t_final=float(stat_f[F_T_FINAL]),
        final_state=b.y_end,
        amplitude=float(stat_f[F_AMPLITUDE]),
        t_converged=float(stat_f[F_T_CONVERGED]),
        rest_time=float(stat_f[F_REST_TIME]),
        t=t,
        y=y,
        settings=s,
        switching=(
            {k: int(stat_i[I_TO_STIFF + j]) for j, k in enumerate(AUTO_STATS)}
            if s.method == "auto"
            else None
        ),
    )
