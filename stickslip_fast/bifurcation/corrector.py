"""The Newton corrector of pseudo-arclength continuation, and the locators that use it.

:func:`_correct` solves G(x) = 0 on a hyperplane; :func:`_locate` finds where a test
function changes sign between two branch points (Illinois secant) and
:func:`_locate_change` where an integer property changes (bisection), each trial
corrected onto the branch. Like :mod:`.arclength`, nothing here knows the model."""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np

from .detection import BRANCH_POINT

# evaluate(x) -> (ok, G (m,), DG (m, m + 1), A (m, m)): residual, its Jacobian in (z, lambda),
# and the map's Jacobian in z (whose eigenvalues are the multipliers)
Evaluator = Callable[[np.ndarray], tuple[bool, np.ndarray, np.ndarray, np.ndarray]]


def _tangent(DG: np.ndarray, prev: np.ndarray) -> np.ndarray:
    """Unit null vector of DG (m x (m+1)), oriented along ``prev``."""
    m = DG.shape[0]
    A = np.vstack([DG, prev[None, :]])
    rhs = np.zeros(m + 1)
    rhs[-1] = 1.0
    t = np.linalg.solve(A, rhs)
    return t / np.linalg.norm(t)


#: What :func:`_correct` returns in place of (G, DG, A) when it stopped at the residual's
#: round-off floor: converged as far as the arithmetic allows, but not to ``tol``.
NOISE_FLOOR = "noise-floor"


def _round_off_floor(DG: np.ndarray, x: np.ndarray) -> float:
    """eps ||DG|| ||x|| (max norms): the residual that rounding errors of x's size can cause.

    The evaluation noise of a strongly unstable orbit's return map scales with its
    Jacobian: past the upper fold of Fig. 6's period-1 branch (multiplier 1e2 to 4e3), G
    at x and at x moved by ~1e-14 relative differ from the linear prediction by up to
    0.09-0.35 times this (rtol 1e-11 and 1e-13; docs/orbits.md, "Cost").
    """
    return float(np.finfo(float).eps * np.max(np.abs(DG).sum(axis=1)) * np.max(np.abs(x)))


def _correct(evaluate: Evaluator, x_pred, normal, anchor, tol, max_iter):
    """Newton on [G(x); normal . (x - anchor)] = 0 from x_pred.

    Converged when max |G| <= tol and |normal . (x - anchor)| <= tol. Fails early
    (docs/orbits.md, "Cost") where more iterations would only resample the
    evaluation's noise:

    - at the round-off floor: the Newton update is below ``tol`` and max |G|,
      above ``tol``, is below :func:`_round_off_floor` and did not halve in this
      iteration (returned with :data:`NOISE_FLOOR` in place of the data);
    - stalled: in Newton's local regime (update below sqrt(tol)), two iterations
      in a row did not halve the smallest residual so far.

    Neither accepts a point the plain test would reject.

    Returns
    -------
    (converged, x, (G, DG, A) or None or NOISE_FLOOR, iterations)
    """
    x = x_pred.copy()
    best, stalled = math.inf, 0
    for it in range(max_iter + 1):
        ok, G, DG, A = evaluate(x)
        if not ok:
            return False, x, None, it
        res = float(np.max(np.abs(G)))
        h = float(normal @ (x - anchor))
        if res <= tol and abs(h) <= tol:
            return True, x, (G, DG, A), it
        # Newton near a root gains digits quadratically: a residual that does not halve
        # is noise (the integration's or the rounding's), not progress
        if res < 0.5 * best:
            best, stalled = res, 0
        else:
            stalled += 1
        J = np.vstack([DG, normal[None, :]])
        try:
            dx = np.linalg.solve(J, -np.r_[G, h])
        except np.linalg.LinAlgError:
            return False, x, None, it
        step = float(np.max(np.abs(dx)))
        if stalled and step <= tol and abs(h) <= tol and res <= _round_off_floor(DG, x):
            return False, x, NOISE_FLOOR, it
        if stalled >= 2 and step <= math.sqrt(tol):
            return False, x, None, it
        if it == max_iter:
            break
        x = x + dx
        if not np.all(np.isfinite(x)):
            return False, x, None, it
    return False, x, None, max_iter


def _locate(evaluate, xa, xb, kind, fa, fb, t_a, tol, locate_tol, test_fn):
    """Illinois secant in sigma in [0, 1] on the chord xa -> xb, correcting each point.

    Done when lambda moves less than ``locate_tol``. Near a branch point G is quadratic
    in the distance from it, so a point there is found only to ~sqrt(tol); and the
    corrector, which has two branches to choose from there, may fail: a branch point's
    trial that fails is tried again at the middle of the bracket (up to 3 times)."""
    chord = xb - xa
    normal = chord / np.linalg.norm(chord)
    a, b = 0.0, 1.0
    side = 0
    x_best = None
    lam_prev = math.inf
    retries = 3 if kind == BRANCH_POINT else 0

    def trial(sig):  # the chord's point at sig, corrected onto the branch
        anchor = xa + sig * chord
        return _correct(evaluate, anchor, normal, anchor, tol, 8)

    for _ in range(60):
        sig = (a * fb - b * fa) / (fb - fa)
        if not a < sig < b:
            sig = 0.5 * (a + b)
        okc, x, data, _ = trial(sig)
        while not okc and retries and sig != 0.5 * (a + b):
            retries -= 1
            sig = 0.5 * (a + b)
            okc, x, data, _ = trial(sig)
        if not okc:
            return x_best
        _, DG, A = data
        f = test_fn(A, DG, _tangent(DG, t_a))[kind]
        x_best = x
        if abs(x[-1] - lam_prev) <= locate_tol or f == 0.0 or b - a < 1e-14:
            return x
        lam_prev = x[-1]
        if f * fa > 0:
            a, fa = sig, f
            if side == -1:
                fb *= 0.5
            side = -1
        else:
            b, fb = sig, f
            if side == 1:
                fa *= 0.5
            side = 1
    return x_best


def _locate_change(evaluate, xa, xb, count_a, count_at, tol, locate_tol):
    """Bisection on the chord xa -> xb (each trial corrected onto the branch) for where
    the integer ``count_at(x)`` stops being ``count_a``; returns the first point past it
    (xb if no trial converges), within ``locate_tol`` in the parameter."""
    chord = xb - xa
    normal = chord / np.linalg.norm(chord)
    a, b = 0.0, 1.0
    x_past = xb
    for _ in range(60):
        if abs(chord[-1]) * (b - a) <= locate_tol:
            break
        sig = 0.5 * (a + b)
        anchor = xa + sig * chord
        okc, x, _, _ = _correct(evaluate, anchor, normal, anchor, tol, 8)
        if not okc:
            break
        try:
            same = count_at(x) == count_a
        except ValueError:  # the orbit could not be sampled there
            break
        if same:
            a = sig
        else:
            b = sig
            x_past = x
    return x_past
