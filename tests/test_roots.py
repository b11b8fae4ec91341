"""base/roots.py: Brent's method against SciPy's brentq (the same tolerance) on standard
test functions, and its refusals."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.optimize import brentq

from stickslip_fast.base.roots import brent_root

EPS = float(np.finfo(float).eps)

# (f, a, b, exact root or None): smooth, flat, steep, a jump, a root at a bound's side
CASES = [
    (lambda x: x**3 - 2 * x - 5, 2.0, 3.0, None),  # Wallis's cubic, 2.0945514815423265
    (lambda x: math.cos(x) - x, 0.0, 1.0, None),
    (lambda x: (x - 1.0) ** 11, 0.5, 2.0, 1.0),  # flat: ~110-130 evaluations at 1e-12
    (lambda x: math.tanh(1e6 * (x - 0.3)), 0.0, 1.0, 0.3),  # a step 1e-6 wide
    (lambda x: -1.0 if x < 1 / 3 else 1.0, 0.0, 1.0, 1 / 3),  # a jump: bisection only
    (lambda x: math.exp(x) - 1e-12, -40.0, 0.0, math.log(1e-12)),
    (lambda x: x * math.exp(-x) - 0.1, 0.0, 1.0, None),
    (lambda x: math.sin(x), 3.0, 4.0, math.pi),
    (lambda x: x - 1e-300, -1.0, 1.0, 1e-300),  # a root at the underflow's edge
]


@pytest.mark.parametrize("case", range(len(CASES)))
@pytest.mark.parametrize("xtol", [2e-12, 1e-13, 1e-6])
def test_the_root_is_scipys_to_the_tolerance(case, xtol):
    f, a, b, exact = CASES[case]
    calls = []

    def counted(x):
        calls.append(x)
        return f(x)

    mine = brent_root(counted, a, b, xtol=xtol, rtol=4 * EPS, max_iter=500)
    ref, info = brentq(f, a, b, xtol=xtol, rtol=4 * EPS, full_output=True, maxiter=500)
    tol = xtol + 4 * EPS * abs(ref)
    assert abs(mine - ref) <= tol, (mine, ref)
    if exact is not None:
        assert abs(mine - exact) <= tol
    # as many evaluations as SciPy's, give or take a few (both are Brent's method; on most
    # of these they take the same steps to the bit)
    assert len(calls) <= info.function_calls + 5, (len(calls), info.function_calls)


def test_an_exact_zero_and_the_refusals():
    assert brent_root(lambda x: x - 0.5, 0.5, 2.0) == 0.5  # at a bound
    assert brent_root(lambda x: x - 0.5, 0.0, 1.0) == 0.5  # the first secant step hits it
    with pytest.raises(ValueError, match="opposite signs"):
        brent_root(lambda x: x * x + 1, -1.0, 1.0)
    with pytest.raises(ValueError, match="must be finite"):
        brent_root(lambda x: x, -math.inf, 1.0)
    with pytest.raises(ValueError, match="not finite"):
        brent_root(lambda x: math.nan if x > 0.2 else x - 0.5, 0.0, 1.0)
    with pytest.raises(ValueError, match="no convergence"):
        brent_root(lambda x: -1.0 if x < 1 / 3 else 1.0, 0.0, 1.0, xtol=0.0, rtol=0.0, max_iter=20)
