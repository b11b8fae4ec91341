"""A Neimark-Sacker point of the model itself (issue 28): two disks on one DC motor.

On the asymmetric set with two disks on a DC motor, the period-2 orbit that the paper's
start reaches at eta = 6 (docs/lyapunov.md) stays stable down to eta = 5.0205606069,
where a complex pair of multipliers near -1 (angle ~177.5 degrees, so not a
period-doubling) leaves the unit circle. The multipliers are checked against central
finite differences of the return map (no variational equations), and brute force shows
what the point means: above it the orbit attracts, below it the disks fall to steady
sliding (docs/orbits.md, "The model").
"""

from __future__ import annotations

import warnings

import numpy as np
import pytest

import stickslip_fast as ssf

ETA_START = 5.020708294113684
# its period-2 orbit's section point (x1, dx1, phi1, dphi1, x2, dx2, phi2, dphi2, v_b), from
# a continuation of the orbit the paper's start reaches at eta = 6 (docs/orbits.md)
Z_START = [0.02418354385284989, 0.0, 0.12324497669065838, -0.003342450409824975,
           0.12051249803510332, 0.009363839230134646, 0.04333063921307841,
           1.1487765237205487e-06, 0.00936507653236205]  # fmt: skip
ETA_NS = 5.0205606069  # located three ways (two continuations and this test's), to 3e-11


def _system(eta):
    return ssf.System.preset("asymmetric", drive="dc-motor", n_oscillators=2, eta=eta)


def _fd_multipliers(system, z, T, h=1e-8):
    """Eigenvalues of the period-2 return map by central differences (rtol 1e-13): the
    map is so nonlinear near the stick band that h = 1e-6 is off by orders of magnitude."""
    keep = [0, 2, 3, 4, 5, 6, 7, 8]  # dx1 = 0 on the section

    def image(y):
        r = ssf.simulate(system, 1.25 * T, y0=y, rtol=1e-13, atol=1e-15, max_points=10)
        return r.poincare[np.nonzero(r.t_poincare > 0.75 * T)[0][0]]

    jac = np.empty((8, 8))
    for col, k in enumerate(keep):
        up, down = np.array(z, dtype=float), np.array(z, dtype=float)
        up[k] += h
        down[k] -= h
        jac[:, col] = ((image(up) - image(down)) / (2 * h))[keep]
    mu = np.linalg.eigvals(jac)
    return mu[np.argsort(-np.abs(mu))]


@pytest.fixture(scope="module")
def branch():
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        orbit = ssf.find_orbit(_system(ETA_START), Z_START, period=2)
        assert orbit.converged and orbit.stable and orbit.residual < 1e-10
        # the lower bound 1.5e-5 past the point, so that the step before it is an interior
        # one (5.0205717; an orbit branch ends on a bound by a step along the tangent, and
        # with the bound at 5.02055 it got there from 5.0206302 directly)
        return ssf.continue_orbit(
            orbit, "eta", (5.02054, 5.02071), direction=-1, max_points=20, stick_events=False
        )


def test_the_period_2_orbit_loses_stability_at_a_neimark_sacker_point(branch):
    ns = [b for b in branch.bifurcations if b.kind == "neimark-sacker"]
    assert len(ns) == 1 and abs(ns[0].value - ETA_NS) < 1e-9
    i = ns[0].index
    stable_side, unstable_side = branch.multipliers[i], branch.multipliers[i + 1]
    assert branch.stable[i] and not branch.stable[i + 1]
    # the critical pair is complex, near -1 but not at it: a torus, not a doubling
    for mu in (stable_side, unstable_side):
        pair = mu[np.abs(mu.imag) > 0.02]  # the one complex pair
        assert pair.size == 2 and pair[0] == np.conj(pair[1])
        assert 176.5 < abs(np.degrees(np.angle(pair[0]))) < 178.5
    # |pair| 0.80234 -> 1.34 (at 5.02055; the branch's end is now 5.02054); the real
    # multiplier 0.79 -> 0.8175 stays inside
    assert np.max(np.abs(stable_side)) < 0.81 and np.max(np.abs(unstable_side)) > 1.3
    assert np.sort(np.abs(unstable_side))[-3] < 0.82


def test_the_multipliers_on_both_sides_match_finite_differences(branch):
    i = [b for b in branch.bifurcations if b.kind == "neimark-sacker"][0].index
    for j in (i, i + 1):
        system = _system(float(branch.values[j]))
        fd = _fd_multipliers(system, branch.points[j], float(branch.T[j]))
        mu = np.asarray(branch.multipliers[j])
        mu = mu[np.argsort(-np.abs(mu))]
        # measured: 0.80234 / 1.34274 (variational) against finite differences within 1e-3
        np.testing.assert_allclose(np.abs(fd[:3]), np.abs(mu[:3]), rtol=2e-3)
        np.testing.assert_allclose(np.abs(np.angle(fd[:3])), np.abs(np.angle(mu[:3])), atol=2e-3)


def test_brute_force_above_the_point_stays_on_the_orbit_and_falls_to_sliding_below(branch):
    i = [b for b in branch.bifurcations if b.kind == "neimark-sacker"][0].index
    above = ssf.simulate(_system(float(branch.values[i])), 20000, y0=branch.points[i])
    assert (above.status, above.period) == ("ok", 2)
    # one of the last two points (period 2) is the orbit's section point
    assert min(np.abs(p - branch.points[i]).max() for p in above.poincare[-2:]) < 1e-6
    below = ssf.simulate(_system(float(branch.values[i + 1])), 20000, y0=branch.points[i + 1])
    assert below.status == "equilibrium"
