"""Where the period-1 region of Fig. 6 closes in (eta, k12) (issue 28, item 4;
docs/reproduction.md, "The fold curve in (eta, k12)"): the two folds of the stable period-1
orbit meet at a quadratic minimum of the fold curve, k12_min = -0.8317150 at eta = 2.6193.
Three one-parameter continuations, about 40 s warm on the shared 2-core VM."""

from __future__ import annotations

import numpy as np

import stickslip_fast as ssf

# the stable period-1 orbit at eta = 2.6, k12 = -0.8316 (find_orbit)
Z = np.array([0.11834572437245043, 0.0, 0.1459190815849308, -0.008125583378266665])
K_ABOVE = -0.8316
#: k12 of the fold curve's minimum: the vertex of a parabola through the folds in k12 of
#: one-parameter branches at eta = 2.61, 2.6194, 2.63 (docs/reproduction.md)
K12_MIN, ETA_MIN, CURVATURE = -0.83171498, 2.6193, 0.0489


def _fold(eta, k12, param, bounds, direction):
    orbit = ssf.find_orbit(ssf.System.preset("asymmetric", eta=eta, k12=k12), Z, 1)
    assert orbit.converged and abs(orbit.multipliers[0]) < 0.2, orbit
    branch = ssf.continue_orbit(orbit, param, bounds, ds=1e-3, ds_max=5e-3, max_points=300,
                                stick_events=False, direction=direction)  # fmt: skip
    folds = [b for b in branch.bifurcations if b.kind == "fold"]
    assert len(folds) == 1, branch.summary()
    return folds[0].value


def test_period_one_region_closes_at_a_minimum_of_the_fold_curve():
    # just above the minimum: a stable period-1 interval between two folds
    upper = _fold(2.6, K_ABOVE, "eta", (2.6, 2.8), 1)
    lower = _fold(2.6, K_ABOVE, "eta", (2.4, 2.6), -1)
    assert abs(upper - 2.6673481248) < 1e-8 and abs(lower - 2.5705528075) < 1e-8
    # at its middle the fold in k12 is the curve's minimum (within CURVATURE * 3e-4^2)
    mid = 0.5 * (upper + lower)
    k12_fold = _fold(mid, K_ABOVE, "k12", (-0.84, K_ABOVE), -1)
    assert abs(k12_fold - K12_MIN) < 3e-8 and abs(mid - ETA_MIN) < 1e-3
    # a quadratic minimum (the folds' distance grows as the square root of k12 - k12_min;
    # a cusp would give the power 3/2): k12 - k12_min = CURVATURE (half-width)^2 to 3 %
    half = 0.5 * (upper - lower)
    assert abs((K_ABOVE - k12_fold) / (CURVATURE * half**2) - 1) < 0.03
