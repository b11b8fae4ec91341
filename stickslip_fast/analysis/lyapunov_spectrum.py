"""The Lyapunov spectrum: the k largest exponents by the QR method, and the Kaplan-Yorke dimension.

:func:`lyapunov_spectrum` runs :func:`~.lyapunov_kernel.lyapunov_kernel` with k
tangent vectors (:func:`~.lyapunov.largest_lyapunov` is its k = 1 case); see
docs/lyapunov.md, "The spectrum", for what it can and cannot resolve on this model.
"""

from __future__ import annotations

import math
import numbers
import warnings
from dataclasses import dataclass, field

import numpy as np

from ..model.system import System
from .lyapunov import (
    DEFAULT_LYAP_RTOL,
    check_inputs,
    default_frame,
    fit_slope,
)
from .lyapunov_kernel import run_tangents

__all__ = ["LyapunovSpectrum", "lyapunov_spectrum", "kaplan_yorke"]


_SPECTRUM_DOC = """The k largest Lyapunov exponents from the variational equations (QR method).

    Integrates y' = f(y) with k tangent vectors u_j' = J(y) u_j (the analytic
    Jacobian and its second derivatives; compiled Rodas5P on the augmented
    system), and re-orthonormalises the vectors by Gram-Schmidt (Benettin et
    al. 1980; Shimada and Nagashima 1979): exponent j is the mean growth rate
    of the j-th vector's length after it lost its projections on the ones
    before it, over [t_transient, t_end].

    Parameters
    ----------
    system : System
    t_end : float
        Final time.
    t_transient : float
        Averaging starts at the first step end at or after this time; before it
        only the directions of the vectors evolve.
    y0 : array_like, optional
        Initial state (default zeros, as in :func:`stickslip_fast.simulate`).
    rtol, atol : float, optional
        Tolerances of the state, as for :func:`~stickslip_fast.largest_lyapunov`
        (rtol 1e-8; atol 1e-10, or 1e-5 eps where eps is below 1e-5).
    renorm_dt : float
        Minimum time between the records of ``convergence``. With k > 1 the
        vectors are re-orthonormalised after every step whatever it is; with
        k = 1 the one vector is renormalised at the records.
    k : int
        How many exponents, the largest first: 1 to ``system.n_state``; needed
        unless ``frame`` gives them. There is no default because the cost
        depends so much on it: where disks stick, the exponents of the stuck
        directions are of order -1000 and resolving them takes steps of their
        time scale (see Notes).
    frame : array_like, shape (k, n_state), optional
        The vectors' start (orthonormalised in order); default fixed
        pseudo-random rows (seed 12345) whose first row is the default ``u0`` of
        :func:`largest_lyapunov`. Its rows must be linearly independent.
    tangent_atol : float
        Absolute tolerance of each vector relative to its length (as in
        :func:`largest_lyapunov`).
    max_steps : int
        Give up with status "max-steps" after this many accepted steps.

    Returns
    -------
    LyapunovSpectrum

    Raises
    ------
    ValueError
        For a ``k`` or ``frame`` that does not fit the system (naming it), and
        for the arguments :func:`largest_lyapunov` refuses.

    Notes
    -----
    **Stick phases.** While a disk sticks, its slip velocities are held by a
    friction slope of order mu / eps: on the presets (eps = 1e-5) the trace of
    J reaches -3e4 and averages -9000 over the period-1 orbit at eta = 2.0.
    The two directions a stick phase locks have exponents of that order (there
    -2570 and -6430, beside 0 and -0.2421). A vector along them forces steps of
    their time scale: the full spectrum of that orbit took 44 million steps for
    t = 1300 (85 s), the two leading exponents 158 000 steps for t = 3000
    (0.2 s). Ask for the stuck directions only when they matter.

    Checks (tests/test_lyapunov_spectrum.py): at a stable equilibrium the
    exponents are the real parts of the Jacobian's eigenvalues; on a periodic
    orbit the leading ones are 0 and ``log|mu| / T`` of its leading Floquet
    multiplier; all n sum to ``divergence`` (to 1e-6 relative on the period-1
    orbit, where that is -9000); the first exponents do not depend on k; with
    ``k = 1`` the result is :func:`largest_lyapunov`'s exponent.

    Examples
    --------
    >>> import stickslip_fast as ssf
    >>> system = ssf.System.preset("asymmetric", eta=2.0)
    >>> spec = ssf.lyapunov_spectrum(system, 3000, 1000, k=2)
    >>> spec.exponents_fit, spec.resolved  # doctest: +SKIP
    (array([ 1.2e-05, -0.24207]), True)
    """


@dataclass
class LyapunovSpectrum:
    """What :func:`lyapunov_spectrum` returns.

    Attributes
    ----------
    exponents : ndarray, shape (k,)
        The k largest Lyapunov exponents (plain averages of log R_jj over the
        window), in the order of the QR flow, which is descending except where
        two exponents are equal to within the run's noise (a complex pair at
        an equilibrium). NaN if the run failed before t_transient.
    exponents_fit : ndarray, shape (k,)
        Least-squares slopes of each cumulative log growth, as
        :attr:`LyapunovResult.exponent_fit` (less biased where the growth
        oscillates along a periodic orbit).
    kaplan_yorke : float
        :func:`kaplan_yorke` of ``exponents_fit`` (of ``exponents`` where a fit
        is NaN: under two records); NaN if it depends on an unresolved exponent.
        On a periodic orbit the first exponent is 0 to within the run's noise,
        so it is 1 or 0 by the sign of that noise.
    divergence : float
        The mean of the divergence trace J(y) over the window. All n exponents
        sum to it (Liouville's formula), so it checks the ones computed.
    resolved : ndarray of bool, shape (k,)
        False for exponent j if its vector, or one before it, shrank below the
        float range (1e-290) within a step of the window: the contraction beyond
        that is lost, and the vectors after it are orthogonalised against an
        arbitrary replacement. With k = n and none flagged so, all are False if
        their sum misses ``divergence`` by more than 1 % of
        ``max(1, abs(divergence))`` (Liouville's formula). An unresolved
        exponent comes with a ``RuntimeWarning``.
    convergence : ndarray, shape (records, 1 + k)
        Time and the k running estimates at each renormalisation after t_transient.
    status : str
        "ok", "nonfinite", "step-underflow", "max-steps" or "interrupted".
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

    exponents: np.ndarray
    exponents_fit: np.ndarray
    kaplan_yorke: float
    divergence: float
    resolved: np.ndarray
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
        shown = ", ".join(f"{x:.6g}" for x in self.exponents)
        return (
            f"LyapunovSpectrum(exponents=[{shown}], kaplan_yorke={self.kaplan_yorke:.6g}, "
            f"divergence={self.divergence:.6g}, resolved={self.resolved.tolist()}, "
            f"status={self.status!r}, n_steps={self.n_steps}, runtime={self.runtime:.3g}s)"
        )


def lyapunov_spectrum(
    system: System,
    t_end: float,
    t_transient: float = 0.0,
    y0: np.ndarray | list | None = None,
    rtol: float = DEFAULT_LYAP_RTOL,
    atol: float | None = None,
    renorm_dt: float = 1.0,
    *,
    k: int | None = None,
    frame: np.ndarray | list | None = None,
    tangent_atol: float = 1e-8,
    max_steps: int = 50_000_000,
) -> LyapunovSpectrum:
    y_init, atol, tangent_atol = check_inputs(
        system, t_end, t_transient, y0, rtol, atol, renorm_dt, tangent_atol
    )
    start = _frame(system.n_state, k, frame)
    run = run_tangents(
        system, y_init, start, t_end, t_transient, rtol, atol, tangent_atol, renorm_dt, max_steps
    )
    fits = np.array([
        fit_slope(run.convergence[:, [0, 1 + j]], run.t_start) for j in range(start.shape[0])
    ])  # fmt: skip
    resolved = resolved_flags(run.vanished, run.exponents, run.divergence, system.n_state)
    _warn_unresolved(run, resolved)
    return LyapunovSpectrum(
        exponents=run.exponents,
        exponents_fit=fits,
        kaplan_yorke=_resolved_kaplan_yorke(
            np.where(np.isfinite(fits), fits, run.exponents), resolved
        ),
        divergence=run.divergence,
        resolved=resolved,
        convergence=run.convergence,
        **dict(run.run_fields(), settings=dict(run.settings, k=int(start.shape[0]))),
    )


lyapunov_spectrum.__doc__ = _SPECTRUM_DOC


def _warn_unresolved(run, resolved: np.ndarray) -> None:
    """A RuntimeWarning naming the exponents that are not resolved (``resolved`` False)."""
    if run.status != "ok":
        return
    if not resolved.all():
        bad = ", ".join(str(j + 1) for j in np.flatnonzero(~resolved))
        warnings.warn(
            f"lyapunov_spectrum: exponent(s) {bad} of {resolved.size} are not resolved: a vector "
            "shrank beyond the float range within a step, or the sum misses the mean divergence "
            f"{run.divergence:.6g}, which all exponents sum to; try a smaller rtol or "
            "tangent_atol",
            RuntimeWarning,
            stacklevel=3,
        )


def resolved_flags(
    vanished: np.ndarray, exponents: np.ndarray, divergence: float, n: int
) -> np.ndarray:
    """Which of k exponents are resolved (see :attr:`LyapunovSpectrum.resolved`).

    ``vanished`` counts, per vector, the steps after which it had to be replaced;
    ``n`` is the state's size (the sum rule applies when all n are computed).
    """
    # a replaced vector is arbitrary, and so is the subspace of the ones after it
    resolved = np.cumsum(vanished) == 0
    if resolved.size == n and resolved.all() and not sum_matches(exponents, divergence):
        resolved[:] = False  # some contraction was lost, and no vector says which
    return resolved


def sum_matches(exponents: np.ndarray, divergence: float, rel: float = 0.01) -> bool:
    """Whether a full spectrum sums to the mean divergence (Liouville's formula), to
    ``rel`` of ``max(1, abs(divergence))``."""
    total = float(np.sum(exponents))
    return abs(total - divergence) <= rel * max(1.0, abs(divergence))


def _resolved_kaplan_yorke(exponents: np.ndarray, resolved: np.ndarray) -> float:
    """:func:`kaplan_yorke`, or NaN where it uses an unresolved exponent (D needs the
    exponents up to the first after floor(D))."""
    dim = kaplan_yorke(exponents)
    if math.isnan(dim):
        return dim
    used = min(int(math.floor(dim)) + 1, exponents.size)
    order = np.argsort(exponents)[::-1]
    return dim if resolved[order[:used]].all() else math.nan


def _frame(n: int, k, frame) -> np.ndarray:
    """The start of the tangent vectors, (k, n), checked against ``k`` and the state size."""
    if k is not None and (isinstance(k, bool) or not isinstance(k, numbers.Integral)):
        raise ValueError(f"k must be an integer, got {k!r}")
    if frame is None:
        if k is None:
            raise ValueError(f"k (how many exponents, 1 to {n}) is needed when frame is not given")
        k = int(k)
        if not 1 <= k <= n:
            raise ValueError(f"k must be in [1, {n}] (the state's size), got {k}")
        return default_frame(n, k)
    rows = np.array(frame, dtype=float, ndmin=2)
    if rows.ndim != 2 or rows.shape[1] != n or not 1 <= rows.shape[0] <= n:
        raise ValueError(f"frame must have shape (k, {n}) with 1 <= k <= {n}, got {rows.shape}")
    if k is not None and int(k) != rows.shape[0]:
        raise ValueError(f"k ({k}) differs from the rows of frame ({rows.shape[0]})")
    if not np.all(np.isfinite(rows)):
        raise ValueError("frame must be finite")
    sv = np.linalg.svd(rows, compute_uv=False)
    if not sv[-1] > 1e-12 * sv[0]:
        raise ValueError("the rows of frame must be linearly independent")
    return rows


def kaplan_yorke(exponents: np.ndarray | list) -> float:
    """The Lyapunov (Kaplan-Yorke) dimension of a spectrum.

    With the exponents sorted in decreasing order and j the largest count whose
    partial sum S_j = lambda_1 + ... + lambda_j is >= 0, ``D = j + S_j / abs(lambda_(j+1))``.

    Parameters
    ----------
    exponents : array_like
        Lyapunov exponents, in any order.

    Returns
    -------
    float
        0.0 if the largest exponent is negative (a stable equilibrium); the number
        of exponents if every partial sum is >= 0 (for a partial spectrum a lower
        bound); NaN if any exponent is NaN. For a periodic orbit, whose largest
        exponent is 0 to within the run's noise, it is 1 or 0 with the sign of that noise.

    Examples
    --------
    >>> round(kaplan_yorke([0.9056, 0.0, -14.5723]), 4)  # the Lorenz attractor
    2.0621
    """
    lam = np.sort(np.asarray(exponents, dtype=float).ravel())[::-1]
    if lam.size == 0 or not np.all(np.isfinite(lam)):
        return math.nan
    sums = np.cumsum(lam)
    nonneg = np.flatnonzero(sums >= 0.0)
    if nonneg.size == 0:
        return 0.0
    j = int(nonneg[-1]) + 1
    if j == lam.size:
        return float(j)
    return j + float(sums[j - 1]) / abs(float(lam[j]))
