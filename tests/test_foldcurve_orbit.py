"""The fold curve of Fig. 6's period-1 orbits in (eta, k12) against one-parameter folds
(issue 28, item 5). About 20 s warm: the curve and four one-parameter continuations
to a sharp fold."""

from __future__ import annotations

import numpy as np

import stickslip_fast as ssf

# the stable period-1 orbit at eta = 3.3, k12 = -0.8 (find_orbit)
Z33 = np.array([0.07332092304307371, 0.0, 0.12221581726865255, -0.00674109106906407])


def _fold_branch(k12, eta, max_points=100):
    s = ssf.System.preset("asymmetric", eta=eta, k12=k12)
    orbit = ssf.find_orbit(s, Z33, 1)
    assert orbit.converged, orbit
    branch = ssf.continue_orbit(orbit, "eta", (eta, eta + 0.05), ds=2e-3, ds_max=5e-3,
                                max_points=max_points, stick_events=False)  # fmt: skip
    folds = [b for b in branch.bifurcations if b.kind == "fold"]
    assert folds, branch.summary()
    return branch, folds[0]


def test_fold_curve_passes_through_one_parameter_folds():
    branch, fold = _fold_branch(-0.8, 3.30)
    assert abs(fold.value - 3.3236646195) < 1e-8  # docs/limits.md
    curve = ssf.continue_bifurcation(branch, fold, "k12", (-0.806, -0.79), direction=-1,
                                     ds=0.002, ds_max=0.01, max_points=40)  # fmt: skip
    assert curve.status == "bounds" and curve.values[-1, 1] == -0.806
    assert curve.kind == "fold" and curve.codim2 == []
    np.testing.assert_allclose(curve.values[0], [fold.value, -0.8], atol=1e-9)
    # a multiplier at +1 all along (to the fold's square-root sensitivity: |1 - mu| ~ 400
    # sqrt(distance in eta), and the curve is corrected to 1e-10)
    assert np.all(np.abs(np.abs(curve.multipliers[:, 0]) - 1) < 5e-3)
    assert np.all(np.diff(curve.values[:, 1]) < 0) and np.all(np.diff(curve.values[:, 0]) < 0)
    for j in (len(curve.values) // 3, 2 * len(curve.values) // 3, -1):
        eta_c, k12 = curve.values[j]
        # stopped a few points past the fold (not along the whole unstable side)
        _, fold_k = _fold_branch(float(k12), float(eta_c) - 0.02, max_points=25)
        assert abs(fold_k.value - eta_c) < 1e-8, (k12, fold_k.value, eta_c)
