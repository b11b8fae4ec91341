"""The largest Lyapunov exponent (Benettin), and the inputs the Lyapunov functions share.

:func:`largest_lyapunov` runs :func:`~.lyapunov_kernel.lyapunov_kernel`, the state
and tangent vectors of the variational equations on the one adaptive driver with
Rodas5P, with one vector; :func:`~.lyapunov_spectrum.lyapunov_spectrum` with k.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from ..base.messages import plain
from ..core.settings import warn_if_coarse_atol
from ..model.system import System
from .lyapunov_kernel import lyapunov_kernel, run_tangents

__all__ = ["LyapunovResult", "largest_lyapunov", "lyapunov_kernel", "default_lyapunov_atol"]

DEFAULT_LYAP_RTOL = 1e-8
DEFAULT_LYAP_ATOL = 1e-10
#: The default atol per unit of eps below the presets' eps = 1e-5 (DEFAULT_LYAP_ATOL / 1e-5;
#: see :func:`default_lyapunov_atol`).
LYAP_ATOL_PER_EPS = 1e-5


def default_lyapunov_atol(eps: float) -> float:
    """The Lyapunov functions' default atol for the friction law's ``eps``.

    :data:`DEFAULT_LYAP_ATOL` (1e-10, which is 1e-5 eps at the presets' eps = 1e-5), and
    :data:`LYAP_ATOL_PER_EPS` ``eps`` below that, as
    :func:`~stickslip_fast.core.settings.default_atol` for ``simulate``. At eps = 1e-8 a
    fixed 1e-10 (1e-2 eps) gave -0.0081 for Fig. 6's period-2 orbit at eta = 6.0 and
    -0.032 at eta = 9.99, where atol = 1e-4 eps ... 1e-6 eps gives -0.00008 and +0.0015
    (the values at eps = 1e-5: +0.00025 and +0.0016).
    """
    return min(DEFAULT_LYAP_ATOL, LYAP_ATOL_PER_EPS * eps)


_LARGEST_DOC = """Largest Lyapunov exponent from the variational equations (Benettin).

    Integrates y' = f(y) and u' = J(y) u with the analytic Jacobian, using a
    compiled Rodas5P kernel on the augmented autonomous system, and averages
    the log growth of ``|u|`` over [t_transient, t_end].

    Parameters
    ----------
    system : System
    t_end : float
        Final time.
    t_transient : float
        Averaging starts at the first step end at or after this time; before it
        only the direction of u evolves.
    y0 : array_like, optional
        Initial state (default zeros, as in :func:`stickslip_fast.simulate`).
    rtol, atol : float, optional
        Tolerances of the y part. Defaults: rtol 1e-8; atol 1e-10, and 1e-5 eps where
        the friction law's eps is below 1e-5 (:func:`default_lyapunov_atol`). An atol
        above 1e-4 eps leaves the creep of a sticking disk unresolved and gives a
        :class:`~stickslip_fast.CoarseToleranceWarning`.
    renorm_dt : float
        Minimum time between renormalisations (and convergence records).
    u0 : array_like, optional
        Initial tangent vector; default a fixed pseudo-random unit vector
        (seed 12345), which has components along every direction.
    tangent_atol : float
        Absolute tolerance of the tangent part relative to ``|u|`` (default 1e-8:
        on the presets the exponent agrees with 1e-10 to ~1e-6 at a third fewer
        steps).
    max_steps : int
        Give up with status "max-steps" after this many accepted steps.

    Returns
    -------
    LyapunovResult

    Notes
    -----
    For a periodic orbit of an autonomous system the largest exponent is 0
    (the flow direction neither grows nor shrinks on average); the finite-time
    estimate carries a bias of order ``log(|f(y_end)| / |f(y_start)|)`` / (t_end -
    t_start), which decays like 1 / t_end.

    Examples
    --------
    >>> from stickslip_fast import System
    >>> res = largest_lyapunov(System.preset("symmetric", eta=5.0), 6000, 1000)
    >>> abs(res.exponent) < 1e-3  # doctest: +SKIP
    True
    """


@dataclass
class LyapunovResult:
    """What :func:`largest_lyapunov` returns.

    Attributes
    ----------
    exponent : float
        Largest Lyapunov exponent (Benettin): ``log(|u(t_final)| / |u(t_start)|)``
        / (t_final - t_start), NaN if the run failed before t_transient.
    exponent_fit : float
        Least-squares slope of the cumulative log growth L(t) over the
        convergence records. Same limit; for a periodic orbit the bounded
        periodic part of L biases it only by O(1 / T^2) instead of O(1 / T).
    convergence : ndarray, shape (k, 2)
        Columns (t, running estimate) at each renormalisation after t_transient.
    status : str
        "ok", "nonfinite", "step-underflow" or "max-steps".
    t_start, t_final : float
        Averaging window (t_start is the first step end at or after t_transient).
    n_steps, n_rejected : int
        Accepted and rejected steps of the augmented system.
    final_state : ndarray
        State y at t_final.
    runtime : float
        Wall-clock seconds of the compiled kernel.
    settings : dict
    """

    exponent: float
    exponent_fit: float
    convergence: np.ndarray
    status: str
    t_start: float
    t_final: float
    n_steps: int
    n_rejected: int
    final_state: np.ndarray
    runtime: float
    settings: dict = field(default_factory=dict)

    def __repr__(self) -> str:
        return (
            f"LyapunovResult(exponent={self.exponent:.6g}, exponent_fit={self.exponent_fit:.6g}, "
            f"status={self.status!r}, "
            f"n_steps={self.n_steps}, runtime={self.runtime:.3g}s)"
        )


def largest_lyapunov(
    system: System,
    t_end: float,
    t_transient: float = 0.0,
    y0: np.ndarray | list | None = None,
    rtol: float = DEFAULT_LYAP_RTOL,
    atol: float | None = None,
    renorm_dt: float = 1.0,
    *,
    u0: np.ndarray | list | None = None,
    tangent_atol: float = 1e-8,
    max_steps: int = 50_000_000,
) -> LyapunovResult:
    y_init, atol, tangent_atol = check_inputs(
        system, t_end, t_transient, y0, rtol, atol, renorm_dt, tangent_atol
    )
    n = system.n_state
    if u0 is None:
        u_init = default_frame(n, 1)[0]
    else:
        u_init = np.asarray(u0, dtype=float)
        if u_init.shape != (n,) or not np.all(np.isfinite(u_init)) or not np.any(u_init):
            raise ValueError(f"u0 must be a finite nonzero vector of length {n}")
    run = run_tangents(
        system, y_init, u_init[None, :], t_end, t_transient, rtol, atol, tangent_atol, renorm_dt,
        max_steps,
    )  # fmt: skip
    conv = run.convergence[:, :2]
    return LyapunovResult(
        exponent=float(run.exponents[0]),
        exponent_fit=fit_slope(conv, run.t_start),
        convergence=conv,
        **run.run_fields(),
    )


largest_lyapunov.__doc__ = _LARGEST_DOC


def default_frame(n: int, k: int) -> np.ndarray:
    """The default start of the k tangent vectors: fixed pseudo-random rows (seed 12345).

    Their components lie along every direction; row 0 is the default ``u0`` of
    :func:`largest_lyapunov`, so the spectrum's first exponent is that one.
    """
    return np.random.default_rng(12345).standard_normal((k, n))


def check_inputs(system, t_end, t_transient, y0, rtol, atol, renorm_dt, tangent_atol):
    """Check the arguments the Lyapunov functions share; the initial state, ``atol`` (the
    default where None) and ``tangent_atol`` as the kernel takes them. Warns (for the
    public function that called it) if ``atol`` is coarse against eps."""
    if not isinstance(system, System):
        raise TypeError(f"system must be a stickslip_fast.System, got {type(system).__name__}")
    if atol is None:
        atol = default_lyapunov_atol(system.eps)
    for name, value in (("t_end", t_end), ("rtol", rtol), ("atol", atol), ("renorm_dt", renorm_dt)):
        if not (math.isfinite(value) and value > 0):
            raise ValueError(f"{name} must be finite and > 0, got {plain(value)}")
    if not (math.isfinite(t_transient) and 0 <= t_transient < t_end):
        raise ValueError(f"t_transient must be in [0, t_end), got {plain(t_transient)}")
    tangent_atol = float(tangent_atol)
    if not (math.isfinite(tangent_atol) and tangent_atol > 0):
        raise ValueError(f"tangent_atol must be finite and > 0, got {plain(tangent_atol)}")
    y_init = system.initial_state(y0)
    warn_if_coarse_atol(system.eps, atol, stacklevel=3)
    return y_init, atol, tangent_atol


def fit_slope(conv: np.ndarray, t_start: float) -> float:
    """Least-squares slope of the accumulated log growth against time (NaN below 2 records).

    ``conv`` holds (t, running estimate) rows; the growth is estimate * (t - t_start).
    """
    k = len(conv)
    if k >= 2:
        tt = np.concatenate([[t_start], conv[:, 0]])
        growth = np.concatenate([[0.0], conv[:, 1] * (conv[:, 0] - t_start)])
        slope = float(np.polyfit(tt, growth, 1)[0])
    else:
        slope = math.nan
    return slope
