"""Lyapunov spectrum (QR method): against the linearisation at an equilibrium, the Floquet
multipliers of a periodic orbit, Liouville's formula, and the largest exponent."""

from __future__ import annotations

import math
import warnings

import numpy as np
import pytest

import stickslip_fast as ssf
from stickslip_fast.base.jit import python_callable
from stickslip_fast.model.equations import dense_jacobian, rhs

ASYM = ssf.System.preset("asymmetric", eta=2.0)


def _fd_jacobian(system: ssf.System, y: np.ndarray) -> np.ndarray:
    """Central differences of the right-hand side: a Jacobian that does not use the analytic one."""
    f = python_callable(rhs)
    p = system.to_array()
    p[ssf.model.params.P_ETAP] = ssf.model.params.eta_prime(system.eta)
    n = y.size
    jac = np.empty((n, n))
    for c in range(n):
        h = 1e-7 * max(1.0, abs(y[c]))
        up, dn = np.zeros(n), np.zeros(n)
        e = np.zeros(n)
        e[c] = h
        f(y + e, p, system.n_oscillators, system.is_dc_motor, up)
        f(y - e, p, system.n_oscillators, system.is_dc_motor, dn)
        jac[:, c] = (up - dn) / (2 * h)
    return jac


def _mean_trace(system: ssf.System, samples: np.ndarray) -> float:
    """The divergence averaged over uniform samples of a trajectory (analytic Jacobian)."""
    p = system.to_array()
    p[ssf.model.params.P_ETAP] = ssf.model.params.eta_prime(system.eta)
    n_osc, dc = system.n_oscillators, system.is_dc_motor
    return float(np.mean([np.trace(dense_jacobian(y, p, n_osc, dc)) for y in samples]))


def test_equilibrium_spectrum_is_the_real_parts_of_the_eigenvalues():
    # the stable steady sliding at eta = 2.0: u' = J u with J constant, so the exponents are
    # the real parts of J's eigenvalues (a complex pair twice), J here by finite differences
    eq = ssf.find_equilibrium(ASYM)
    assert eq.stable
    reference = np.sort(np.linalg.eigvals(_fd_jacobian(ASYM, eq.state)).real)[::-1]
    spec = ssf.lyapunov_spectrum(ASYM, 4000.0, 0.0, y0=eq.state, k=4)
    assert spec.status == "ok" and spec.resolved.all()
    np.testing.assert_allclose(np.sort(spec.exponents_fit)[::-1], reference, atol=5e-4)
    # all four sum to the trace exactly (Liouville), whatever the rotation of the pair
    assert spec.exponents.sum() == pytest.approx(reference.sum(), abs=1e-6)
    assert spec.divergence == pytest.approx(reference.sum(), rel=1e-9)
    assert spec.kaplan_yorke == 0.0
    assert spec.convergence.shape[1] == 5


def test_periodic_orbit_leading_exponents_are_its_floquet_exponents(p1_orbit):
    # the period-1 orbit at eta = 2.0 (Fig. 6): 0 along the flow, then log|mu| / T of its
    # leading multiplier from find_orbit's monodromy (Newton on the Poincare map)
    orbit = p1_orbit
    mu = orbit.multipliers[np.argmax(np.abs(orbit.multipliers))]
    spec = ssf.lyapunov_spectrum(ASYM, 3000.0, 1000.0, y0=orbit.points[0], k=2)
    assert spec.status == "ok" and spec.resolved.all()
    assert abs(spec.exponents_fit[0]) < 1e-4
    assert spec.exponents_fit[1] == pytest.approx(math.log(abs(mu)) / orbit.T, abs=2e-4)
    assert spec.kaplan_yorke == pytest.approx(1.0, abs=0.01) or spec.kaplan_yorke == 0.0
    # the window's mean divergence: the stick phase dominates it (~ -9000)
    one_period = ssf.simulate(ASYM, orbit.T, 0.0, y0=orbit.points[0], rtol=1e-11, atol=1e-13,
                              sample_dt=2e-4)  # fmt: skip
    assert spec.divergence == pytest.approx(_mean_trace(ASYM, one_period.y), rel=0.01)
    assert spec.divergence < -1000


@pytest.fixture(scope="module")
def p1_orbit():
    return ssf.find_orbit(ASYM, ssf.simulate(ASYM, 3000, stop="converged"))


def test_full_spectrum_of_the_orbit_sums_to_the_divergence(p1_orbit):
    # all four on two periods of the orbit: the stick phase's two directions have
    # exponents of order -1000 (the divergence averages ~ -9000), resolved by steps of
    # their time scale; Liouville: the four sum to the mean divergence
    t_end = 2 * p1_orbit.T
    spec = ssf.lyapunov_spectrum(ASYM, t_end, 0.0, y0=p1_orbit.points[0], k=4)
    assert spec.status == "ok" and spec.resolved.all()
    assert spec.exponents.sum() == pytest.approx(spec.divergence, rel=1e-5)
    samples = ssf.simulate(ASYM, t_end, 0.0, y0=p1_orbit.points[0], rtol=1e-11, atol=1e-13,
                           sample_dt=2e-4)  # fmt: skip
    assert spec.divergence == pytest.approx(_mean_trace(ASYM, samples.y), rel=0.01)
    assert spec.exponents[2] < -1000 and spec.exponents[3] < -1000
    # the first exponents do not depend on how many are computed
    three = ssf.lyapunov_spectrum(ASYM, t_end, 0.0, y0=p1_orbit.points[0], k=3)
    np.testing.assert_allclose(three.exponents, spec.exponents[:3], rtol=1e-3, atol=1e-4)


def test_resolved_flags():
    from stickslip_fast.analysis.lyapunov_spectrum import resolved_flags

    lam = np.array([0.0, -0.24, -2570.0, -6430.0])
    ok = resolved_flags(np.zeros(4, dtype=np.int64), lam, -9000.24, 4)
    assert ok.tolist() == [True, True, True, True]
    # a vector replaced: it and the ones after it are arbitrary
    assert resolved_flags(np.array([0, 0, 1, 0]), lam, -9000.24, 4).tolist() == [
        True, True, False, False]  # fmt: skip
    # all n computed and the sum misses the divergence by more than 1 %: none trusted
    assert not resolved_flags(np.zeros(4, dtype=np.int64), lam, -9200.0, 4).any()
    # fewer than n: no sum to check
    assert resolved_flags(np.zeros(2, dtype=np.int64), lam[:2], -9200.0, 4).all()


def test_unresolved_exponents_warn():
    from types import SimpleNamespace

    from stickslip_fast.analysis.lyapunov_spectrum import _warn_unresolved

    run = SimpleNamespace(status="ok", divergence=-9000.0)
    with pytest.warns(RuntimeWarning, match=r"exponent\(s\) 3, 4 of 4 are not resolved"):
        _warn_unresolved(run, np.array([True, True, False, False]))
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        _warn_unresolved(run, np.array([True, True]))  # nothing to say
        _warn_unresolved(
            SimpleNamespace(status="max-steps", divergence=np.nan), np.array([False])
        )  # fmt: skip  (the status says it)


def test_two_disks_on_a_motor_divergence_and_leading_exponent():
    # N = 2 on the DC motor (n = 9): the divergence includes the motor's own term, and
    # the first vector is Benettin's largest exponent's
    system = ssf.System.preset("asymmetric", eta=1.5, n_oscillators=2, drive="dc-motor")
    y0 = [0.1, 0.0, 0.0, 0.0, 0.0, 0.0, 0.1, 0.0, system.vb0]
    spec = ssf.lyapunov_spectrum(system, 400.0, 100.0, y0=y0, k=2)
    assert spec.status == "ok"
    largest = ssf.largest_lyapunov(system, 400.0, 100.0, y0=y0)
    assert spec.exponents[0] == pytest.approx(largest.exponent, abs=2e-3)
    run = ssf.simulate(system, 400.0, 100.0, y0=y0, rtol=1e-10, atol=1e-12, sample_dt=2e-3)
    assert spec.divergence == pytest.approx(_mean_trace(system, run.y), rel=0.02)


def test_one_vector_is_the_largest_exponent():
    system = ssf.System.preset("asymmetric", eta=9.99)
    spec = ssf.lyapunov_spectrum(system, 600.0, 200.0, k=1)
    largest = ssf.largest_lyapunov(system, 600.0, 200.0)
    assert spec.exponents[0] == largest.exponent
    assert spec.exponents_fit[0] == largest.exponent_fit
    np.testing.assert_array_equal(spec.convergence, largest.convergence)


def test_kaplan_yorke_dimension():
    assert ssf.kaplan_yorke([0.9056, 0.0, -14.5723]) == pytest.approx(2.06214, abs=1e-5)  # Lorenz
    assert ssf.kaplan_yorke([-14.5723, 0.9056, 0.0]) == pytest.approx(2.06214, abs=1e-5)
    assert ssf.kaplan_yorke([-0.1, -2.0]) == 0.0
    assert ssf.kaplan_yorke([0.0, -0.2421]) == 1.0
    assert ssf.kaplan_yorke([0.3, 0.1]) == 2.0  # every partial sum >= 0: the count
    assert math.isnan(ssf.kaplan_yorke([0.1, math.nan]))


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({}, "k \\(how many exponents, 1 to 4\\) is needed"),
        ({"k": 0}, "k must be in \\[1, 4\\]"),
        ({"k": 5}, "k must be in \\[1, 4\\]"),
        ({"k": True}, "k must be an integer"),
        ({"k": 2.0}, "k must be an integer"),
        ({"frame": np.eye(3)}, "frame must have shape \\(k, 4\\)"),
        ({"frame": np.ones((2, 4))}, "linearly independent"),
        ({"frame": np.eye(4)[:2], "k": 3}, "k \\(3\\) differs from the rows of frame \\(2\\)"),
        ({"frame": np.full((1, 4), np.nan)}, "frame must be finite"),
        ({"k": 2, "renorm_dt": 0.0}, "renorm_dt must be finite and > 0"),
        ({"k": 2, "tangent_atol": -1.0}, "tangent_atol must be finite and > 0"),
    ],
)
def test_bad_arguments_are_named(kwargs, match):
    with pytest.raises(ValueError, match=match):
        ssf.lyapunov_spectrum(ASYM, 10.0, **kwargs)


def test_a_given_frame_is_used_in_order():
    # the first row alone decides the first exponent: e_1 gives the same as k = 1 from e_1
    frame = np.eye(4)[[0, 2]]
    spec = ssf.lyapunov_spectrum(ASYM, 300.0, 100.0, frame=frame)
    largest = ssf.largest_lyapunov(ASYM, 300.0, 100.0, u0=np.eye(4)[0])
    assert spec.settings["k"] == 2
    assert spec.exponents.shape == (2,)
    assert spec.exponents[0] == pytest.approx(largest.exponent, abs=1e-3)


def test_the_default_atol_follows_a_small_eps():
    # a stable period-2 orbit (Fig. 6, eta = 6.0) has largest exponent 0 (along the
    # flow); at eps = 1e-8 the old fixed atol 1e-10 (1e-2 eps) gave -0.0081 over these
    # 1000 time units, atol = 1e-4 ... 1e-6 eps -0.00008 (analysis/lyapunov.py)
    from stickslip_fast.analysis.lyapunov import default_lyapunov_atol

    assert default_lyapunov_atol(1e-5) == 1e-10 == default_lyapunov_atol(1.0)
    assert default_lyapunov_atol(1e-8) == 1e-5 * 1e-8
    sharp = ssf.System.preset("asymmetric", eta=6.0, eps=1e-8)
    with warnings.catch_warnings():
        warnings.simplefilter("error", ssf.CoarseToleranceWarning)
        lam = ssf.largest_lyapunov(sharp, 2000.0, 1000.0)
        spec = ssf.lyapunov_spectrum(sharp, 2000.0, 1000.0, k=2)
    assert lam.settings["atol"] == spec.settings["atol"] == default_lyapunov_atol(1e-8)
    assert abs(lam.exponent) < 1e-3 and abs(spec.exponents[0]) < 1e-3
    with pytest.warns(ssf.CoarseToleranceWarning, match="eps = 1e-08") as rec:
        ssf.largest_lyapunov(sharp, 2000.0, 1000.0, atol=1e-10)
    assert rec[0].filename == __file__
