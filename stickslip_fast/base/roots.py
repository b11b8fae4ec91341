"""A bracketed scalar root: Brent's method, so that the package needs no SciPy at run time.

SciPy is a test extra only (pyproject.toml). Until 2026-12-02 the stick-phase curves
imported ``scipy.optimize.brentq`` at module level, and with it ``import stickslip_fast``
failed on an install of the runtime dependencies alone.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

__all__ = ["brent_root"]

_EPS = float(np.finfo(float).eps)


def brent_root(
    f: Callable[[float], float],
    a: float,
    b: float,
    *,
    xtol: float = 2e-12,
    rtol: float = 4 * _EPS,
    max_iter: int = 100,
) -> float:
    """A root of ``f`` in [a, b], where f(a) and f(b) have opposite signs.

    Brent's method (Brent 1973, "Algorithms for Minimization without Derivatives",
    ch. 4): inverse quadratic interpolation or the secant step where they stay well
    inside the bracket and shrink it fast enough, bisection otherwise; the bracket
    [b, c] around the root is kept throughout. Returns when half the bracket is at most
    ``(xtol + rtol |x|) / 2`` (the tolerance of ``scipy.optimize.brentq``, against which
    tests/test_roots.py checks it), or when f is exactly 0.

    Raises
    ------
    ValueError
        If f(a) and f(b) do not have opposite signs, a bound or a value of f is not
        finite, or the bracket is not reduced to the tolerance within ``max_iter``
        evaluations.
    """
    a, b = float(a), float(b)
    if not (np.isfinite(a) and np.isfinite(b)):
        raise ValueError(f"the bracket [{a}, {b}] must be finite")
    fa, fb = _value(f, a), _value(f, b)
    if fa == 0.0:
        return a
    if fb == 0.0:
        return b
    if (fa > 0.0) == (fb > 0.0):
        raise ValueError(f"f(a) = {fa:g} and f(b) = {fb:g} must have opposite signs")
    c, fc = a, fa
    d = e = b - a
    for _ in range(max_iter):
        if (fb > 0.0) == (fc > 0.0):  # the root lies between b and a: c takes a's place
            c, fc = a, fa
            d = e = b - a
        if abs(fc) < abs(fb):  # b is the best estimate so far
            a, b, c = b, c, b
            fa, fb, fc = fb, fc, fb
        tol = 0.5 * (xtol + rtol * abs(b))
        m = 0.5 * (c - b)
        if fb == 0.0 or abs(m) <= tol:
            return b
        if abs(e) >= tol and abs(fa) > abs(fb):
            s = fb / fa
            if a == c:  # two points: the secant
                p, q = 2.0 * m * s, 1.0 - s
            else:  # three points: inverse quadratic interpolation
                qa, r = fa / fc, fb / fc
                p = s * (2.0 * m * qa * (qa - r) - (b - a) * (r - 1.0))
                q = (qa - 1.0) * (r - 1.0) * (s - 1.0)
            if p > 0.0:
                q = -q
            else:
                p = -p
            # accept it if it lands inside the bracket and beats half the step before last
            if 2.0 * p < 3.0 * m * q - abs(tol * q) and p < abs(0.5 * e * q):
                e, d = d, p / q
            else:
                d = e = m
        else:
            d = e = m
        a, fa = b, fb
        b += d if abs(d) > tol else (tol if m > 0.0 else -tol)
        fb = _value(f, b)
    raise ValueError(f"no convergence to the tolerance in {max_iter} evaluations")


def _value(f: Callable[[float], float], x: float) -> float:
    y = float(f(x))
    if not np.isfinite(y):
        raise ValueError(f"f({x!r}) = {y} is not finite")
    return y
