"""The pseudo-arclength predictor-corrector on any smooth map given as a callable.

It knows nothing of the model, so it is tested on maps whose bifurcations are known in
closed form; :mod:`.orbit_branch` and :mod:`.equilibrium_branch` give it their evaluators."""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from .corrector import NOISE_FLOOR, Evaluator, _correct, _locate, _tangent
from .detection import BRANCH_POINT, _sorted_eigs, _tests, branch_point_test, singular_gaps
from .progress import walk_reporter

#: A branch ends with status "precision-limit" where its last this many steps together
#: advance less than the ``ds_min`` given (possible only in the tighter stages).
STALL_WINDOW = 10


#: :func:`pseudo_arclength`'s docstring (kept out of the function body, like
#: :func:`~stickslip_fast.analysis.census.census`'s: its parameters take more lines than
#: the code, and the layout rule counts a function's lines).
_PSEUDO_ARCLENGTH_DOC = """Follow G(x) = 0, x = (z, lambda), by pseudo-arclength continuation.

Parameters
----------
evaluate : callable
    x -> (ok, G, DG, A): the residual, its Jacobian (m x (m + 1)) and the
    map's Jacobian in z (m x m; its eigenvalues are the multipliers).
x0 : ndarray, shape (m + 1,)
    A solution (G(x0) ~ 0).
direction : float
    +1 to start towards increasing lambda, -1 towards decreasing.
bounds : (float, float)
    The branch ends on the first of them it reaches: a step that would
    leave [lo, hi] ends on the bound instead, corrected with lambda fixed there
    (with ``branch_points``, after a step to it along the tangent).
ds, ds_min, ds_max : float
    First, smallest and largest arclength step. The step grows by 1.5
    after a corrector that needed <= 3 iterations, halves after a failure.
max_points : int
tol : float
    Corrector tolerance on max |G|.
locate_tol : float
    Bifurcations are located (Illinois secant on the test function along
    the chord between two branch points) until lambda moves less than this.
max_corrector : int
    Most corrector iterations per step.
jump : callable, optional
    (x_old, x_new) -> True when x_new is not on the same smooth branch
    (for orbits: the period in time jumped). Such a step, like a failed
    corrector or one that moved more than ds / 2 from the predictor, is
    rejected and ds halved. When ds falls below ds_min and the last
    rejection was a jump, the branch ends with status "nonsmooth" within
    ds_min of the discontinuity; otherwise with "step-too-small".
tests : callable
    (A, tangent) -> {kind: value}: test functions whose sign changes mark
    bifurcations (default: those of a map's fixed points, fold /
    period-doubling / Neimark-Sacker; equilibria use fold / Hopf).
spectrum : callable, optional
    A -> the eigenvalues recorded per point (default: by modulus, largest first).
orient : ndarray, optional
    Orients the first tangent instead of ``direction`` (its sign along
    ``orient``): a branch resumed in new coordinates (a re-meshed multiple
    shooting) keeps its sense through a fold.
stall_ds_min : float, optional
    The ``ds_min`` of the stall test (default ``ds_min``; a resumed branch
    passes the one given first).
branch_points : bool
    Also mark branch points (kind "branch-point": the sign of det [DG; tᵀ],
    :func:`.detection.branch_point_test`; a fold located in the same step as a
    branch point is the branch point: a pitchfork's side branch turns there). Such
    a walk also ends on a bound by a step along the tangent first: corrected with
    lambda fixed from the full step's predictor, a branch near a fold could land on
    its other sheet, and the test would read a branch point between them. (Curves
    keep the fixed-lambda correction: their ends are checked against one-parameter
    folds to 1e-6, and the tangent step moved one by 1.6e-6.)
noise_gap : float
    Read no fold and no branch point from a step with an end where DG's smallest
    singular value is below ``noise_gap`` times its largest
    (:func:`.detection.rank_gap`): DG has a second null direction to within its
    noise there, and the tangent is noise (orbits: :data:`.detection.RANK_GAP_MIN`;
    default 0, off). Where DG's smallest singular value is also below ``noise_gap``
    times the next one (:func:`.detection.singular_gaps`: not merely small against
    one huge multiplier) at :data:`STALL_WINDOW` points in a row, the branch ends
    with status "degenerate".
stop : callable, optional
    (x, A, walk) -> True ends the branch after accepting x (its map's Jacobian
    A) with status "stopped" (for a change of coordinates; ``walk`` holds the
    step size and the settings in force).
refine : sequence of (evaluate, tol, ds_min)
    Tighter settings to go on with, in turn, where the corrector fails at
    ``ds_min`` (not where the steps jump off the branch): the last point is
    corrected again with the next stage's evaluator and ``tol`` (or, if
    that fails, one of the few before it: :func:`_restart`; the points after
    it are dropped), and the continuation resumes from it with
    ``ds = ds_min`` and the stage's smaller ``ds_min``. The branch ends when
    no stage is left (or no recent point can be corrected with it). For sharp folds whose turn is
    narrower than ``ds_min`` or whose parameter extent is below ``tol`` over
    the residual's sensitivity to lambda (docs/limits.md).

Returns
-------
xs, mults, bifs, status
    The points (k, m + 1), their multipliers (k, m), the located
    bifurcations (kind, lambda, index, x) and the reason the branch ended:
    "bounds", "max-points", "step-too-small" (the corrector failed),
    "nonsmooth" (steps kept jumping off the branch), "stopped" (``stop``) or
    "precision-limit"
    (with ``refine``: the last :data:`STALL_WINDOW` steps together advanced
    less than ``ds_min``; or the last corrector stopped at the residual's
    round-off floor, :func:`_correct`, with no stage left) or "degenerate"
    (with ``noise_gap``: at each of the last :data:`STALL_WINDOW` points DG's
    smallest singular value was below ``noise_gap`` times the next one, so the
    solutions form a surface there, not a curve, within the noise, and the
    tangent is noise).
"""


def pseudo_arclength(
    evaluate: Evaluator,
    x0: np.ndarray,
    direction: float,
    bounds: tuple[float, float],
    *,
    ds: float,
    ds_min: float,
    ds_max: float,
    max_points: int,
    tol: float,
    locate_tol: float = 1e-9,
    max_corrector: int = 6,
    jump: Callable[[np.ndarray, np.ndarray], bool] | None = None,
    tests: Callable[[np.ndarray, np.ndarray], dict[str, float]] = _tests,
    spectrum: Callable[[np.ndarray], np.ndarray] | None = None,
    refine: Sequence[tuple[Evaluator, float, float]] = (),
    orient: np.ndarray | None = None,
    stall_ds_min: float | None = None,
    stop: Callable[[np.ndarray, Any, Any], bool] | None = None,
    branch_points: bool = False,
    noise_gap: float = 0.0,
):
    walk = _Walk.start(evaluate, x0, direction, tol, ds, ds_min, refine,
                       _test_function(tests, branch_points), spectrum or _sorted_eigs, orient,
                       noise_gap)  # fmt: skip
    stall_ds = ds_min if stall_ds_min is None else stall_ds_min
    lo, hi = bounds
    status = "max-points"
    with walk_reporter() as report:  # the progress bar, if one is shown
        while len(walk.xs) < max_points:
            x = walk.xs[-1]
            trial, walk.ds = _try_steps(walk.evaluate, x, walk.t, walk.ds, walk.ds_min,
                                        (lo, hi), walk.tol, max_corrector, jump,
                                        branch_points)  # fmt: skip
            if not trial.accepted:
                # a step that jumped off the branch ends it; a sharp end may go on, tighter
                if not trial.jumped and walk.next_stage(max_corrector):
                    continue
                status = "nonsmooth" if trial.jumped else "step-too-small"
                if trial.floored:  # the residual's noise, not the step, stopped the corrector
                    status = "precision-limit"
                break
            walk.accept(x, trial.x_new, trial.data, locate_tol)
            if report is not None:
                report(trial.x_new)
            if trial.on_bound:
                status = "bounds"
                break
            if walk.degenerate():
                status = "degenerate"
                break
            if _stalled(walk.xs, stall_ds):  # the ds_min given: the stages lower walk.ds_min
                status = "precision-limit"
                break
            if trial.its <= 3:
                walk.ds = min(walk.ds * 1.5, ds_max)
            if stop is not None and stop(trial.x_new, trial.data[2], walk):
                status = "stopped"
                break
    return np.array(walk.xs), np.array(walk.mults), walk.bifs, status


pseudo_arclength.__doc__ = _PSEUDO_ARCLENGTH_DOC


@dataclass
class _Trial:
    """The outcome of :func:`_try_steps`: the accepted point, or why none was.

    ``jumped`` and ``floored`` describe the last rejection (a step that jumped off the
    branch; a corrector that stopped at the residual's round-off floor)."""

    accepted: bool = False
    jumped: bool = False
    floored: bool = False
    on_bound: bool = False
    x_new: np.ndarray | None = None
    data: Any = None
    its: int = 0


def _try_steps(
    evaluate: Evaluator,
    x: np.ndarray,
    t: np.ndarray,
    ds: float,
    ds_min: float,
    bounds: tuple[float, float],
    tol: float,
    max_corrector: int,
    jump: Callable[[np.ndarray, np.ndarray], bool] | None,
    along_tangent: bool = False,
) -> tuple[_Trial, float]:
    """Predict from x along t and correct, halving ds until a step is accepted or ds <
    ds_min; returns the :class:`_Trial` and the step size reached. ``along_tangent``: a
    step that leaves the bounds ends on them along the tangent (:func:`_end_on_bound`)."""
    lo, hi = bounds
    trial = _Trial()
    while ds >= ds_min:
        x_pred = x + ds * t
        if not lo <= x_pred[-1] <= hi:
            okc, x_new, data, its = _end_on_bound(evaluate, x, t, ds, (lo, hi), tol,
                                                  max_corrector, along_tangent)  # fmt: skip
            if okc and not (jump is not None and jump(x, x_new)):
                trial.accepted = trial.on_bound = True
                trial.x_new, trial.data, trial.its = x_new, data, its
                break
            trial.floored = data is NOISE_FLOOR
            ds *= 0.5
            continue
        okc, x_new, data, its = _correct(evaluate, x_pred, t, x_pred, tol, max_corrector)
        trial.jumped = False
        trial.floored = data is NOISE_FLOOR
        if okc:
            trial.jumped = bool(jump is not None and jump(x, x_new))
            # a corrector that went far from the predictor has left the branch
            if not trial.jumped and np.linalg.norm(x_new - x_pred) <= 0.5 * ds:
                trial.accepted = True
                trial.x_new, trial.data, trial.its = x_new, data, its
                break
        ds *= 0.5
    return trial, ds


def _end_on_bound(evaluate, x, t, ds, bounds, tol, max_corrector, along_tangent):
    """The branch's point on the bound that the step of size ``ds`` from x along t crosses.

    Corrected with lambda fixed at the bound, from the full step's predictor or, with
    ``along_tangent``, from a plain step to the bound (the predictor x + ds_b t on it,
    corrected normal to t). From the full step's predictor a branch near a fold could
    land on its other sheet (measured: the crossing branch at the anti-phase orbit's
    first branch point, ended at eta = 1.8, landed on its stable sheet 8.5e-4 away, and
    the branch-point test read a spurious point between the two). Returns
    :func:`_correct`'s (converged, x, data, iterations)."""
    lo, hi = bounds
    start = x + ds * t
    bound = hi if start[-1] > hi else lo
    if along_tangent:
        ds_b = (bound - x[-1]) / t[-1]  # in (0, ds]: the full step crosses the bound
        x_b = x + ds_b * t
        x_b[-1] = bound
        okc, start, data, its = _correct(evaluate, x_b, t, x_b, tol, max_corrector)
        if not okc or np.linalg.norm(start - x_b) > 0.5 * ds_b:  # as for any step
            return False, start, data, its
    start[-1] = bound
    e_lam = np.zeros_like(x)
    e_lam[-1] = 1.0
    return _correct(evaluate, start, e_lam, start, tol, max_corrector)


def _stalled(xs: list[np.ndarray], ds_min_given: float) -> bool:
    """The last :data:`STALL_WINDOW` steps together advanced less than ``ds_min_given``.

    Only the tighter stages take steps below ds_min: a crawl there means that Newton's
    reach has shrunk to the integration's precision (docs/limits.md)."""
    if len(xs) <= STALL_WINDOW:
        return False
    last = np.asarray(xs[-STALL_WINDOW - 1 :])
    return bool(np.linalg.norm(np.diff(last, axis=0), axis=1).sum() < ds_min_given)


def _test_function(tests, branch_points: bool):
    """(A, DG, t) -> the test values: ``tests(A, t)``, and the branch-point test."""

    def test_fn(A, DG, t):
        out = tests(A, t)
        if branch_points:
            out[BRANCH_POINT] = branch_point_test(DG, t)
        return out

    return test_fn


@dataclass
class _Walk:
    """A branch being followed: its points, multipliers, test values and bifurcations so
    far, the tangent at the last point, and the settings in force (a ``refine`` stage
    replaces ``evaluate``, ``tol`` and ``ds_min``). ``test_fn(A, DG, t)``: the test values."""

    evaluate: Evaluator
    tol: float
    ds: float
    ds_min: float
    stages: list[tuple[Evaluator, float, float]]
    test_fn: Callable[[Any, np.ndarray, np.ndarray], dict[str, float]]
    spectrum: Callable[[np.ndarray], np.ndarray]
    t: np.ndarray
    xs: list[np.ndarray] = field(default_factory=list)
    mults: list[np.ndarray] = field(default_factory=list)
    tests: list[dict[str, float]] = field(default_factory=list)
    bifs: list[tuple[str, float, int, np.ndarray]] = field(default_factory=list)
    # per point (with noise_gap), detection.singular_gaps(DG): the rank gap, and the
    # smallest singular value against the next
    gaps: list[tuple[float, float]] = field(default_factory=list)
    noise_gap: float = 0.0

    @classmethod
    def start(cls, evaluate, x0, direction, tol, ds, ds_min, refine, test_fn, spectrum,
              orient=None, noise_gap=0.0) -> _Walk:  # fmt: skip
        """The walk at x0, its tangent oriented by ``direction`` in lambda (or by ``orient``)."""
        ok, G, DG, A = evaluate(x0)
        if not ok:
            raise ValueError("the start could not be evaluated")
        guess = np.zeros(G.size + 1)
        guess[-1] = 1.0 if direction >= 0 else -1.0
        if orient is not None:
            guess = np.asarray(orient, dtype=float)
        t = _tangent(DG, guess)
        walk = cls(evaluate, tol, ds, ds_min, list(refine), test_fn, spectrum, t, [x0.copy()],
                   noise_gap=noise_gap)  # fmt: skip
        walk.mults.append(spectrum(A))
        walk.tests.append(test_fn(A, DG, t))
        walk.gaps.append(walk.gap(DG))
        return walk

    def gap(self, DG: np.ndarray) -> tuple[float, float]:
        """:func:`.detection.singular_gaps` of DG (inf where ``noise_gap`` is off)."""
        return singular_gaps(DG) if self.noise_gap > 0 else (math.inf, math.inf)

    def degenerate(self) -> bool:
        """The last :data:`STALL_WINDOW` points all had a second null direction of DG
        within its noise (``noise_gap``): which way the walk goes is noise there."""
        last = [g[1] for g in self.gaps[-STALL_WINDOW:]]
        return self.noise_gap > 0 and len(last) == STALL_WINDOW and max(last) < self.noise_gap

    def accept(self, x: np.ndarray, x_new: np.ndarray, data, locate_tol: float) -> None:
        """Append x_new (corrected, with ``data`` = (G, DG, A)), locating the bifurcations
        whose test functions change sign between x and x_new."""
        G, DG, A = data
        t_new = _tangent(DG, self.t)
        te = self.test_fn(A, DG, t_new)
        k = len(self.xs) - 1
        changed = {
            kind
            for kind, prev in self.tests[-1].items()
            if math.isfinite(prev) and math.isfinite(te[kind]) and prev * te[kind] < 0
        }
        if BRANCH_POINT in changed:  # a pitchfork's side branch turns at the branch point
            changed.discard("fold")
        gap = self.gap(DG)
        if min(gap[0], self.gaps[-1][0]) < self.noise_gap:  # a second null direction: t is noise
            changed -= {"fold", BRANCH_POINT}
        for kind, prev in self.tests[-1].items():
            cur = te[kind]
            if kind in changed:
                loc = _locate(self.evaluate, x, x_new, kind, prev, cur, self.t, self.tol,
                              locate_tol, self.test_fn)  # fmt: skip
                if loc is not None:
                    self.bifs.append((kind, float(loc[-1]), k, loc))
        self.xs.append(x_new)
        self.mults.append(self.spectrum(A))
        self.tests.append(te)
        self.gaps.append(gap)
        self.t = t_new

    def next_stage(self, max_corrector: int) -> bool:
        """Go on with the next ``refine`` stage that corrects a recent point again
        (:func:`_restart`), dropping the points after it; False when none is left."""
        restart = None
        while self.stages and restart is None:
            self.evaluate, self.tol, ds_min_next = self.stages.pop(0)
            restart = _restart(self.evaluate, self.xs, self.tol, max_corrector)
            if restart is not None:
                self.ds, self.ds_min = self.ds_min, min(self.ds_min, ds_min_next)
        if restart is None:
            return False
        j, x_re, (_, DG, A) = restart
        self.t = _tangent(DG, self.xs[j] - self.xs[j - 1] if j > 0 else self.t)
        del self.xs[j + 1 :], self.mults[j + 1 :], self.tests[j + 1 :], self.gaps[j + 1 :]
        self.gaps[j] = self.gap(DG)
        self.xs[j] = x_re
        self.mults[j] = self.spectrum(A)
        self.tests[j] = self.test_fn(A, DG, self.t)
        self.bifs = [b for b in self.bifs if b[2] < j]
        return True


def _restart(
    evaluate: Evaluator, xs: list[np.ndarray], tol: float, max_corrector: int, back: int = 6
) -> tuple[int, np.ndarray, tuple[np.ndarray, np.ndarray, np.ndarray]] | None:
    """A recent branch point corrected again (with ``evaluate`` and ``tol``), or None.

    Tries the last ``back`` points, newest first, each on the hyperplane through it
    normal to the chord from its predecessor, then with lambda fixed; a result is
    kept if it lies closer to the old point than half that chord (the same branch).
    A point computed to a looser tolerance near a sharp fold can lie past the fold
    (its lambda off by ~tol / |dG/dlambda|), where neither has a solution: the
    search then goes back along the branch. Returns (index, point, (G, DG, A)).
    """
    e_lam = np.zeros_like(xs[-1])
    e_lam[-1] = 1.0
    for j in range(len(xs) - 1, max(len(xs) - 1 - back, -1), -1):
        chord = xs[j] - xs[j - 1] if j > 0 else e_lam
        reach = 0.5 * float(np.linalg.norm(chord)) if j > 0 else math.inf
        for normal in (chord / np.linalg.norm(chord), e_lam):
            okc, x, data, _ = _correct(evaluate, xs[j], normal, xs[j], tol, max_corrector)
            if okc and np.linalg.norm(x - xs[j]) <= reach:
                return j, x, data
    return None
