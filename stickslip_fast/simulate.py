"""Public single-trajectory API: :func:`simulate`."""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from .interrupt import call_interruptible, new_abort_flag
from .poincare import STATUS_NAMES, detect_period
from .system import System
from .trajectory import (
    F_AMPLITUDE,
    F_T_CONVERGED,
    F_T_FINAL,
    I_CROSSINGS,
    I_REJECTED,
    I_SAMPLES,
    I_STEPS,
    METHODS,
    N_STAT_F,
    N_STAT_I,
    integrate,
    unroll_ring,
)

__all__ = ["simulate", "SimulationResult", "DEFAULT_RTOL", "DEFAULT_ATOL", "MAX_PERIOD"]

#: Default tolerances. Over the seven SciPy reference trajectories (presets,
#: both drives, N = 1 and 2, 400-3000 time units with their transients) the
#: Poincare points agree with Radau rtol=1e-10 to 1.8e-7 at worst
#: (tests/test_scipy_crosscheck.py); rtol=1e-8 would give up to 2e-4 there.
DEFAULT_RTOL = 1e-9
DEFAULT_ATOL = 1e-11
#: Longest period :func:`detect_period` looks for.
MAX_PERIOD = 64
#: Period tolerance relative to rtol (see :func:`period_tolerance`).
PERIOD_TOL_FACTOR = 1e4
#: Disk speed (over the recording window) below which a run is at rest:
#: ten times the friction law's smoothing width eps = 1e-5 of the presets.
DEFAULT_EQUILIBRIUM_TOL = 1e-4
DEFAULT_MAX_STEPS = 20_000_000
#: Stop rules: run to t_end ("fixed"), or end once converged ("converged").
STOP_KINDS = ("fixed", "converged")
#: Converged stopping: how long the disks must stay at rest before a run ends
#: as an equilibrium (about 15 periods of the slowest free oscillation, 2 pi sqrt(m)).
DEFAULT_DWELL = 200.0


def period_tolerance(rtol: float) -> float:
    """Tolerance for repeated Poincare points: 1e4 rtol, at least 1e-9 (relative).

    Points are accurate to roughly 100 rtol; the extra factor absorbs the last
    bit of transient decay of orbits whose Floquet multipliers are close to 1.
    """
    return max(PERIOD_TOL_FACTOR * rtol, 1e-9)


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
        Smallest p <= 64 with which the points repeat; 0 if none.
    status : str
        "ok", "equilibrium", "stalled", "no-crossings", "nonfinite",
        "step-underflow" or "max-steps".
    n_steps, n_rejected : int
        Accepted and rejected steps.
    t_final : float
        Time reached (t_end unless the run failed).
    final_state : ndarray, shape (n_state,)
    amplitude : float
        Distance from rest over the recording window: the largest |dx_i| or
        |dphi_i|, or the range of v_b. At rest when below ``equilibrium_tol``.
    t_converged : float
        With ``stop="converged"``: when the run was found converged (NaN if it
        reached t_end first, and always with ``stop="fixed"``).
    t, y : ndarray or None
        Uniform samples from t_transient every ``sample_dt`` (when requested).
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
    t: np.ndarray | None = None
    y: np.ndarray | None = None
    settings: dict = field(default_factory=dict)

    def column(self, name: str) -> np.ndarray:
        """Poincare coordinate ``name`` (e.g. "x1", "phi1") of every point."""
        return self.poincare[:, self.state_names.index(name)]

    def __repr__(self) -> str:
        return (
            f"SimulationResult(status={self.status!r}, period={self.period}, "
            f"points={len(self.t_poincare)}, n_steps={self.n_steps}, method={self.method!r})"
        )


def _check_positive(name: str, value: float, allow_zero: bool = False) -> float:
    value = float(value)
    if not math.isfinite(value) or value < 0 or (value == 0 and not allow_zero):
        raise ValueError(
            f"{name} must be finite and {'>=' if allow_zero else '>'} 0, got {value!r}"
        )
    return value


def resolve_settings(
    method: str,
    t_end: float,
    t_transient: float,
    rtol: float | None,
    atol: float | None,
    h: float | None,
    max_points: int,
    max_steps: int | None,
    equilibrium_tol: float,
    period_tol: float | None,
    stop: str = "fixed",
    dwell: float | None = None,
) -> dict:
    """Validate and complete integration settings (shared by simulate and sweep).

    ``stop`` and ``dwell`` enter the dict only with ``stop="converged"``, so
    the settings (and the configuration hashes of existing result files) of
    fixed-window runs are what they always were.
    """
    if method not in METHODS:
        raise ValueError(f"method must be one of {METHODS}, got {method!r}")
    t_end = _check_positive("t_end", t_end)
    t_transient = _check_positive("t_transient", t_transient, allow_zero=True)
    if t_transient >= t_end:
        raise ValueError(f"t_transient ({t_transient}) must be < t_end ({t_end})")
    rtol = DEFAULT_RTOL if rtol is None else _check_positive("rtol", rtol)
    atol = DEFAULT_ATOL if atol is None else _check_positive("atol", atol)
    if method == "dopri5-fixed" and h is None:
        raise ValueError("method 'dopri5-fixed' needs a step size h")
    if h is not None:
        if method == "dopri5":
            raise ValueError("h is not used by the adaptive 'dopri5'; use 'dopri5-fixed'")
        h = _check_positive("h", h)
        steps_needed = math.ceil(t_end / h) + 1
        max_steps = steps_needed if max_steps is None else int(max_steps)
    else:
        h = 0.0
        max_steps = DEFAULT_MAX_STEPS if max_steps is None else int(max_steps)
    if max_steps < 1:
        raise ValueError(f"max_steps must be >= 1, got {max_steps}")
    if isinstance(max_points, bool) or int(max_points) != max_points or max_points < 0:
        raise ValueError(f"max_points must be an integer >= 0, got {max_points!r}")
    equilibrium_tol = _check_positive("equilibrium_tol", equilibrium_tol)
    period_tol = (
        period_tolerance(rtol) if period_tol is None else _check_positive("period_tol", period_tol)
    )
    if stop not in STOP_KINDS:
        raise ValueError(f"stop must be one of {STOP_KINDS}, got {stop!r}")
    if dwell is not None and stop != "converged":
        raise ValueError("dwell is only used with stop='converged'")
    extra = {}
    if stop == "converged":
        extra = dict(
            stop=stop, dwell=DEFAULT_DWELL if dwell is None else _check_positive("dwell", dwell)
        )
    return dict(
        **extra,
        method=method,
        t_end=t_end,
        t_transient=t_transient,
        rtol=rtol,
        atol=atol,
        h=h,
        max_points=int(max_points),
        max_steps=max_steps,
        equilibrium_tol=equilibrium_tol,
        period_tol=period_tol,
    )


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
    equilibrium_tol: float = DEFAULT_EQUILIBRIUM_TOL,
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
        Points, samples and the amplitude used for classification are taken
        only for t >= t_transient.
    y0 : array_like, optional
        Initial state in ``system.state_names`` order; default zeros
        (v_b(0) = 0 for the DC motor, as in the paper).
    method : {"rodas5p", "dopri5", "dopri5-fixed"}
        ``"rodas5p"`` (default): L-stable Rosenbrock-Wanner, order 5(4), for the
        stiff sticking phases. ``"dopri5"``: adaptive Dormand-Prince 5(4) with PI
        control. ``"dopri5-fixed"``: Dormand-Prince with the fixed step ``h``.
    rtol, atol : float, optional
        Tolerances of the adaptive methods (defaults 1e-9 and 1e-11).
    h : float, optional
        Fixed step size. Required by ``"dopri5-fixed"``; with ``"rodas5p"`` it
        runs the Rosenbrock method with fixed steps (for convergence studies).
    max_points : int
        Keep at most this many points: the most recent ones.
    sample_dt : float, optional
        Also return ``t`` and ``y`` on a uniform grid t_transient + k sample_dt.
    max_steps : int, optional
        Give up with status "max-steps" after this many accepted steps.
    equilibrium_tol : float
        The run counts as at rest ("equilibrium", or "stalled" when a DC motor's
        belt is below 1% of v_b0) when over the recording window no disk velocity
        exceeds this and the belt speed varies by less. Default 1e-4, ten times the presets' eps: inside
        the friction law's stick band a "stuck" disk creeps at O(eps).
    period_tol : float, optional
        Relative tolerance of the period detector (default 1e4 rtol).
    stop : {"fixed", "converged"}
        ``"fixed"`` (default): run to ``t_end`` and record after ``t_transient``.
        ``"converged"``: watch the run from t = 0 (``t_transient`` is not used)
        and end it once it has converged: the Poincare points repeat with a
        period p <= 64 to ``period_tol`` over at least 3 periods and 8 points,
        or the disks have been at rest (speeds, and the belt-speed range, below
        ``equilibrium_tol``) for ``dwell``. An orbit then records max(8, 4 p)
        more points (at most ``max_points``), which are the ones returned.
        ``t_end`` is the cap; ``t_converged`` is NaN when it was reached first.
    dwell : float, optional
        Converged stopping: time at rest before a run ends as an equilibrium
        (default 200, about 15 periods of the slowest free oscillation).

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
    s = resolve_settings(
        method, t_end, t_transient, rtol, atol, h, max_points, max_steps, equilibrium_tol,
        period_tol, stop, dwell,
    )  # fmt: skip
    y_init = system.initial_state(y0)
    n = system.n_state
    if sample_dt is not None:
        sample_dt = _check_positive("sample_dt", sample_dt)
        n_samples = int(math.floor((s["t_end"] - s["t_transient"]) / sample_dt + 1e-9)) + 1
    else:
        n_samples = 0
    ring = np.empty((s["max_points"], n))
    tring = np.empty(s["max_points"])
    samples = np.empty((n_samples, n))
    stat_i = np.zeros(N_STAT_I, dtype=np.int64)
    stat_f = np.zeros(N_STAT_F)
    y_end = np.empty(n)
    code = call_interruptible(
        integrate,
        METHODS.index(s["method"]), y_init, system.to_array(), system.n_oscillators,
        system.is_dc_motor, s["t_end"], s["t_transient"], s["rtol"], s["atol"], s["h"],
        s["max_steps"], s["equilibrium_tol"], ring, tring, samples,
        1.0 if sample_dt is None else sample_dt, y_end, stat_i, stat_f,
        STOP_KINDS.index(stop), s.get("dwell", DEFAULT_DWELL), s["period_tol"], MAX_PERIOD,
        abort=new_abort_flag(),
    )  # fmt: skip
    status = STATUS_NAMES[code]
    n_cross = int(stat_i[I_CROSSINGS])
    k = min(n_cross, s["max_points"])
    pts = np.empty((k, n))
    tp = np.empty(k)
    period = 0
    if status == "ok":
        unroll_ring(ring, tring, n_cross, pts, tp)
        period = int(detect_period(pts, k, s["period_tol"], MAX_PERIOD))
    else:
        pts = pts[:0]
        tp = tp[:0]
    t = y = None
    if sample_dt is not None:
        m = int(stat_i[I_SAMPLES])
        t = s["t_transient"] + sample_dt * np.arange(m)
        y = samples[:m]
    return SimulationResult(
        system=system,
        method=s["method"],
        state_names=system.state_names,
        t_poincare=tp,
        poincare=pts,
        n_crossings=n_cross,
        period=period,
        status=status,
        n_steps=int(stat_i[I_STEPS]),
        n_rejected=int(stat_i[I_REJECTED]),
        t_final=float(stat_f[F_T_FINAL]),
        final_state=y_end,
        amplitude=float(stat_f[F_AMPLITUDE]),
        t_converged=float(stat_f[F_T_CONVERGED]),
        t=t,
        y=y,
        settings=s,
    )
