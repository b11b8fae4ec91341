"""Where the period-1 region of Fig. 6 closes in (eta, k12) (issue 28, item 4;
docs/reproduction.md, "Where the period-1 region closes"): the two folds of the stable
period-1 orbit are the sides of one fold curve with a quadratic minimum in k12,
k12_min = -0.83171498 at eta = 2.6193. About 80 s on the loaded 2-core VM: the curve
through the minimum (61 points) and two one-parameter continuations."""

from __future__ import annotations

import numpy as np

import stickslip_fast as ssf

# the stable period-1 orbit at eta = 2.6, k12 = -0.8316 (find_orbit)
Z = np.array([0.11834572437245043, 0.0, 0.1459190815849308, -0.008125583378266665])
K_ABOVE = -0.8316
#: the folds in eta at k12 = K_ABOVE (one-parameter continuations)
LOWER, UPPER = 2.5705528075, 2.6673481248
#: k12 of the fold curve's minimum: the vertex of a parabola through the folds in k12 of
#: one-parameter branches at eta = 2.61, 2.6194, 2.63 (docs/reproduction.md)
K12_MIN, ETA_MIN = -0.83171498, 2.6193


def _branch(eta, param, bounds, direction):
    orbit = ssf.find_orbit(ssf.System.preset("asymmetric", eta=eta, k12=K_ABOVE), Z, 1)
    assert orbit.converged and abs(orbit.multipliers[0]) < 0.2, orbit
    branch = ssf.continue_orbit(orbit, param, bounds, ds=1e-3, ds_max=5e-3, max_points=300,
                                stick_events=False, direction=direction)  # fmt: skip
    folds = [b for b in branch.bifurcations if b.kind == "fold"]
    assert len(folds) == 1, branch.summary()
    return branch, folds[0]


def test_period_one_region_closes_at_a_minimum_of_the_fold_curve():
    branch, lower = _branch(2.6, "eta", (2.4, 2.6), -1)
    assert abs(lower.value - LOWER) < 1e-8
    # from the lower fold through the minimum to the upper fold (the test function's
    # difference step h must resolve these sharp folds: with h = 1e-7 the curve stalls)
    curve = ssf.continue_bifurcation(branch, lower, "k12", (-0.95, K_ABOVE), direction=-1,
                                     ds=0.005, ds_max=0.05, max_points=120, tol=1e-9,
                                     h=1e-9)  # fmt: skip
    assert curve.status == "bounds" and curve.values[-1, 1] == K_ABOVE
    # back at K_ABOVE on the upper fold (the curve is nearly parallel to eta there:
    # dk12/deta = 0.0047, so 1e-6 in eta is 5e-9 in k12)
    assert abs(curve.values[-1, 0] - UPPER) < 1e-6
    # one codim-2 point, the minimum: an extremum in k12, not a cusp
    assert [p.kind for p in curve.codim2] == ["extremum"], curve.codim2
    eta_x, k12_x = curve.codim2[0].values
    assert abs(k12_x - K12_MIN) < 1e-8 and abs(eta_x - ETA_MIN) < 1e-3
    assert np.all(curve.values[:, 1] >= k12_x - 1e-8)  # the curve's tolerance
    # the one-parameter fold in k12 at the extremum's eta
    _, fold_k = _branch(float(eta_x), "k12", (-0.84, K_ABOVE), -1)
    assert abs(fold_k.value - k12_x) < 1e-8, (fold_k.value, k12_x)
