"""The generic steppers and the driver on standard problems with known solutions.

References are analytic: expm(A t) for a linear system, exp(-2t)/exp(-t) for
Kaps' problem, sin t for Prothero-Robinson; orders are the methods' published
ones (Dormand-Prince 5, Rodas5P 5).
"""

import numpy as np
import pytest
from scipy.linalg import expm

from stickslip_fast import System
from stickslip_fast.base.status import STATUS_NAMES
from stickslip_fast.core.testproblems import (
    Kaps,
    LinearProblem,
    ProtheroRobinson,
    solve_test_problem,
)
from stickslip_fast.core.variational import propagate_sensitivity, propagate_tangents

A_OSC = np.array([[0.0, 1.0], [-1.0, -0.1]])


def _fixed(rosen, prob, y0, t_end, n):
    y, st, ns, nr, t = solve_test_problem(
        rosen, prob, np.asarray(y0, float), t_end, 1e-6, 1e-8, t_end / n, 10 * n
    )
    assert (
        STATUS_NAMES[st] == "ok" and ns in (n, n + 1) and nr == 0 and t == t_end
    )  # n + 1: a round-off sliver
    return y


def _order(hs, errs):
    return np.polyfit(np.log(hs), np.log(errs), 1)[0]


@pytest.mark.parametrize("rosen", [True, False])
def test_nonstiff_kaps_fixed_step_order_5(rosen):
    # eps = 1: Kaps' problem is nonlinear and non-stiff, exact solution (exp(-2t), exp(-t))
    prob = Kaps(1.0)
    exact = np.exp([-4.0, -2.0])
    ns = [10, 20, 40, 80]
    errs = [np.abs(_fixed(rosen, prob, [1.0, 1.0], 2.0, n) - exact).max() for n in ns]
    assert abs(_order(2.0 / np.array(ns), errs) - 5.0) < 0.4, errs


def test_prothero_robinson_order_and_stiff_accuracy():
    # mildly stiff (h lam from -10 to -1.25): full order 5
    ns = [10, 20, 40, 80]
    errs = [
        abs(_fixed(True, ProtheroRobinson(-50.0), [0.0, 0.0], 2.0, n)[0] - np.sin(2.0)) for n in ns
    ]
    assert abs(_order(2.0 / np.array(ns[1:]), errs[1:]) - 5.0) < 0.5, errs
    # very stiff (h lam down to -2e5): stable and accurate at every step size
    errs = [
        abs(_fixed(True, ProtheroRobinson(-1e6), [0.0, 0.0], 2.0, n)[0] - np.sin(2.0)) for n in ns
    ]
    assert max(errs) < 1e-10 and errs == sorted(errs, reverse=True), errs


def test_kaps_very_stiff_adaptive_accuracy_and_cost():
    prob = Kaps(1e-8)
    y, st, ns, nr, t = solve_test_problem(
        True, prob, np.array([1.0, 1.0]), 1.0, 1e-8, 1e-10, 0.0, 10**6
    )
    assert STATUS_NAMES[st] == "ok" and t == 1.0
    np.testing.assert_allclose(y, [np.exp(-2.0), np.exp(-1.0)], rtol=1e-7)
    assert ns < 300  # stiffness costs the implicit method nothing
    # the explicit method is held to tiny steps by stability alone
    _, st, ns, _, t = solve_test_problem(
        False, prob, np.array([1.0, 1.0]), 1.0, 1e-8, 1e-10, 0.0, 20000
    )
    assert STATUS_NAMES[st] == "max-steps" and t < 1e-3


def test_adaptive_linear_tolerance_honoured():
    prob = LinearProblem(A_OSC)
    exact = expm(A_OSC * 20.0) @ np.array([1.0, 0.0])
    for rosen in (True, False):
        y, st, ns, nr, _ = solve_test_problem(
            rosen, prob, np.array([1.0, 0.0]), 20.0, 1e-10, 1e-12, 0.0, 10**6
        )
        assert STATUS_NAMES[st] == "ok"
        assert np.abs(y - exact).max() < 1e-8


def test_kernel_rules_nan_and_bounded_rejections():
    # a problem that is NaN from the start ends at once, classified, never loops
    y, st, ns, nr, _ = solve_test_problem(
        True, Kaps(np.nan), np.array([1.0, 1.0]), 1.0, 1e-8, 1e-10, 0.0, 100
    )
    assert STATUS_NAMES[st] == "nonfinite" and ns == 0 and nr <= 100
    # rejected steps are bounded by max_steps too (here every step is rejected)
    y, st, ns, nr, _ = solve_test_problem(
        False, Kaps(1e-300), np.array([1.0, 1.0]), 1.0, 1e-8, 1e-10, 0.0, 50
    )
    assert STATUS_NAMES[st] in ("max-steps", "nonfinite", "step-underflow") and nr <= 50


@pytest.mark.parametrize("variant", [(), (0,)], ids=["generic", "small"])
def test_state_transition_matrix_of_linear_model_is_expm(variant):
    # mu = 0 removes friction from a constant-belt disk: y' = J y, so Phi(t) = expm(J t)
    from stickslip_fast.model.equations import dense_jacobian

    s = System(mu=0.0, k12=-0.8, c=0.05, c12=0.01, m=2.0)
    p = s.to_array()
    n = s.n_state
    y0 = np.linspace(0.1, 0.3, n)
    jac = dense_jacobian(y0, p, 1, s.is_dc_motor)
    st, y, U, t = propagate_tangents(
        y0,
        np.eye(n),
        p,
        1,
        s.is_dc_motor,
        variant,
        7.0,
        0,
        1e-11,
        1e-13,
        1e-12,
        10**6,
        np.zeros(1, np.int64),
    )
    assert STATUS_NAMES[st] == "ok" and t == 7.0
    np.testing.assert_allclose(U, expm(jac * 7.0), atol=1e-8)


@pytest.mark.parametrize("variant", [(), (0,)], ids=["generic", "small"])
def test_parameter_sensitivity_of_linear_model_is_the_expm_derivative(variant):
    # mu = 0: y' = J(k12) y with J affine in k12, so d/dk12 expm(J t) y0 is exactly the
    # upper-right block of expm([[J, B], [0, J]] t) y0 with B = dJ/dk12 (Van Loan)
    from stickslip_fast.model.equations import dense_jacobian

    k12, h = -0.8, 1e-6
    s = System(mu=0.0, k12=k12, c=0.05, c12=0.01, m=2.0)
    n = s.n_state
    y0 = np.linspace(0.1, 0.3, n)
    jac = dense_jacobian(y0, s.to_array(), 1, False)
    dj = np.zeros((n, n))
    dj[1, 2] = -1.0
    dj[3, 0] = -1.0 / s.m
    big = np.block([[jac, dj], [np.zeros((n, n)), jac]])
    ref = expm(big * 7.0)[:n, n:] @ y0
    p2 = np.stack([System(mu=0.0, k12=k12 + d, c=0.05, c12=0.01, m=2.0).to_array()
                   for d in (h, -h)])  # fmt: skip
    U0 = np.hstack([np.eye(n), np.zeros((n, 1))])
    st, y, U, t = propagate_sensitivity(
        y0, U0, s.to_array(), 1, False, variant, 7.0, 0, 1e-11, 1e-13, 1e-12, p2,
        1.0 / (2 * h), 10**6, np.zeros(1, np.int64),
    )  # fmt: skip
    assert STATUS_NAMES[st] == "ok" and t == 7.0
    np.testing.assert_allclose(U[:, :n], expm(jac * 7.0), atol=1e-8)
    np.testing.assert_allclose(U[:, n], ref, atol=1e-8)
    assert np.max(np.abs(ref)) > 0.05  # the reference is not trivially small
    # the tangent columns are those of the plain tangent kernel, bit for bit
    st0, y_0, U_0, t_0 = propagate_tangents(
        y0, np.eye(n), s.to_array(), 1, False, variant, 7.0, 0, 1e-11, 1e-13, 1e-12, 10**6,
        np.zeros(1, np.int64),
    )  # fmt: skip
    assert STATUS_NAMES[st0] == "ok"
    np.testing.assert_allclose(U_0, U[:, :n], atol=1e-9)
    np.testing.assert_allclose(y_0, y, atol=1e-12)


def test_sensitivity_kernel_rejects_bad_rows():
    s = System(mu=0.0)
    n = s.n_state
    st, y, U, t = propagate_sensitivity(
        np.zeros(n), np.zeros((n, 1)), s.to_array(), 1, False, (), 1.0, 0, 1e-8, 1e-10, 1e-8,
        np.stack([s.to_array()] * 3), 1.0, 1000, np.zeros(1, np.int64),
    )  # fmt: skip
    assert STATUS_NAMES[st] == "error" and np.all(np.isnan(U)) and np.isnan(t)


@pytest.mark.parametrize("drive", ["constant", "dc-motor"])
def test_small_tangent_kernel_is_bit_identical_to_generic(drive):
    # StickSlipTangentSmall: the generic tangent arithmetic with N and the belt known
    # at compile time; one return to the section with the n - 1 tangents of the
    # monodromy, through the stick-slip layer at eta = 2
    from stickslip_fast.core.problems import small_shape

    s = System.preset("asymmetric", eta=2.0, drive=drive)
    n = s.n_state
    y0 = np.zeros(n)
    y0[0] = -0.3
    U0 = np.ascontiguousarray(np.eye(n)[:, 1:])
    runs = [
        propagate_tangents(
            y0,
            U0,
            s.to_array(),
            1,
            s.is_dc_motor,
            v,
            1e3,
            2,
            1e-10,
            1e-12,
            1e-10,
            10**6,
            np.zeros(1, np.int64),
        )  # fmt: skip
        for v in ((), small_shape(1, s.is_dc_motor))
    ]
    (st_g, y_g, U_g, t_g), (st_s, y_s, U_s, t_s) = runs
    assert STATUS_NAMES[st_g] == "ok" and np.isfinite(t_g) and np.all(np.isfinite(U_g))
    assert st_s == st_g and t_s == t_g
    assert np.array_equal(y_s, y_g) and np.array_equal(U_s, U_g)


def test_tangent_kernel_rejects_a_mismatched_variant():
    from stickslip_fast.core.problems import small_shape

    s = System.preset("asymmetric", eta=2.0)
    n = s.n_state
    st, y, U, t = propagate_tangents(
        np.zeros(n), np.eye(n), s.to_array(), 1, False, small_shape(1, True), 10.0, 0,
        1e-8, 1e-10, 1e-8, 1000, np.zeros(1, np.int64),
    )  # fmt: skip
    assert STATUS_NAMES[st] == "error" and np.all(np.isnan(U)) and np.isnan(t)


def test_tangent_problem_step_count_stays_near_the_plain_one():
    # The tangent problem's W must be its exact Jacobian (with the second-derivative
    # block from the partials stored at each step's start). A stale block leaves the
    # results right but the tangents' error estimate large: measured ~50x the steps
    # when Numba's dead-code elimination dropped that store. Correct: 2.1x the plain
    # run's steps at eta = 2 (the tangent also carries error control). One belt: the
    # code under test is shared by both belts and both tangent records.
    import stickslip_fast as ssf

    s = System.preset("asymmetric", eta=2.0)
    lyap = ssf.largest_lyapunov(s, 300.0, 100.0, rtol=1e-8, atol=1e-10)
    plain = ssf.simulate(s, 300.0, rtol=1e-8, atol=1e-10)
    assert lyap.status == "ok" and plain.status in ("ok", "equilibrium")
    assert lyap.n_steps < 4 * plain.n_steps
