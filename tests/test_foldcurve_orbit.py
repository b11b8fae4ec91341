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


def test_a_change_of_stick_phases_along_a_curve_is_a_located_codim2_point(monkeypatch):
    # The fold curve above keeps one stick phase per period (so no "stick-phase" point
    # there). Injected: the orbit "gains" a stick phase below k12 = K. The curve names one
    # codim-2 point "stick-phase", the first point past the change, on the curve and
    # within 1e-8 of K in k12; with stick_events=False it names none.
    import stickslip_fast.bifurcation.curve as curve_module

    real, K = curve_module.stick_phases, -0.8015

    def gains_one_below_k(system, point, T, **kw):
        d = real(system, point, T, **kw)
        return np.r_[d, 1.0] if system.k12 < K else d

    monkeypatch.setattr(curve_module, "stick_phases", gains_one_below_k)
    branch, fold = _fold_branch(-0.8, 3.30)
    kw = dict(direction=-1, ds=0.002, ds_max=0.01, max_points=12)
    curve = ssf.continue_bifurcation(branch, fold, "k12", (-0.806, -0.79), **kw)
    events = [c for c in curve.codim2 if c.kind == "stick-phase"]
    assert len(events) == 1 and len(curve.codim2) == 1, curve.codim2
    eta_e, k12_e = events[0].values
    assert K - 1e-8 <= k12_e < K, k12_e
    i = events[0].index  # between curve points i and i + 1
    assert curve.values[i, 1] >= K > curve.values[i + 1, 1]
    assert (
        min(curve.values[i + 1, 0], curve.values[i, 0]) <= eta_e <= max(curve.values[i : i + 2, 0])
    )
    # on the curve: the fold's multiplier at +1 (to the fold's square-root sensitivity)
    s = branch.system.replace(eta=float(eta_e), k12=float(k12_e))
    o = ssf.find_orbit(s, events[0].point, 1)
    assert abs(abs(o.multipliers[0]) - 1) < 5e-3, o.multipliers
    plain = ssf.continue_bifurcation(branch, fold, "k12", (-0.806, -0.79), stick_events=False,
                                     **kw)  # fmt: skip
    assert plain.codim2 == []
    np.testing.assert_array_equal(plain.values, curve.values)


def test_cli_continue_follows_the_fold_in_a_second_parameter(tmp_path, capsys):
    # `stickslip-fast continue` with [continue].param2: the branch in eta to its upper
    # fold, then the fold curve in k12 into OUTPUT.curve1.h5, equal to the API's curve
    from stickslip_fast.cli import main

    cfg = tmp_path / "fold.toml"
    cfg.write_text(
        '[system]\npreset = "asymmetric"\neta = 3.30\n'
        f"[initial]\ny0 = {Z33.tolist()}\n"
        "[integration]\nt_end = 3000.0\nstop = 'converged'\n"
        "[continue]\nparam = 'eta'\nbounds = [3.30, 3.35]\nds = 2e-3\nds_max = 5e-3\n"
        "max_points = 100\nstick_events = false\n"
        "param2 = 'k12'\nbounds2 = [-0.801, -0.79]\ndirection2 = -1\n"
    )  # fmt: skip
    out = tmp_path / "fold.h5"
    assert main(["continue", str(cfg), "-o", str(out), "--quiet"]) == 0
    branch = ssf.Branch.from_hdf5(out)
    folds = [b for b in branch.bifurcations if b.kind == "fold"]
    assert len(folds) == 1 and abs(folds[0].value - 3.3236646195) < 1e-8
    curve = ssf.Curve.from_hdf5(tmp_path / "fold.curve1.h5")
    assert (curve.kind, curve.param, curve.param2, curve.status) == ("fold", "eta", "k12", "bounds")
    assert curve.values[-1, 1] == -0.801 and curve.codim2 == []
    ref = ssf.continue_bifurcation(branch, folds[0], "k12", (-0.801, -0.79), direction=-1)
    np.testing.assert_allclose(curve.values, ref.values, rtol=0, atol=1e-12)


# a point of Fig. 6's period-2 orbit near its period-doubling at eta = 5.042952433
# (tests/test_continuation.py)
P2_ETA = 5.043198103554579
P2_POINT = np.array([0.027234629670059556, 0.0, 0.12785148813700828, -0.0038733936156032087])


def _period_doubling(eta, k12, z, lo, hi, max_points=12):
    s = ssf.System.preset("asymmetric", eta=eta, k12=k12)
    orbit = ssf.find_orbit(s, z, period=2)
    assert orbit.converged, orbit
    branch = ssf.continue_orbit(orbit, "eta", (lo, hi), ds=2e-5, ds_min=1e-9, ds_max=4e-5,
                                max_points=max_points, direction=-1)  # fmt: skip
    pds = [b for b in branch.bifurcations if b.kind == "period-doubling"]
    assert len(pds) == 1, branch.summary()
    return branch, pds[0]


def test_period_doubling_curve_passes_through_one_parameter_period_doublings():
    # about 35 s warm: the curve (10 points, three tangent integrations per evaluation)
    # and four one-parameter continuations of the period-2 orbit
    branch, pd = _period_doubling(P2_ETA, -0.8, P2_POINT, 5.0428, 5.0433, max_points=8)
    assert abs(pd.value - 5.042952433) < 1e-8
    curve = ssf.continue_bifurcation(branch, pd, "k12", (-0.806, -0.79), direction=-1,
                                     ds=0.002, ds_max=0.005, max_points=12)  # fmt: skip
    assert curve.status == "bounds" and curve.values[-1, 1] == -0.806
    assert curve.kind == "period-doubling" and curve.period == 2 and curve.codim2 == []
    np.testing.assert_allclose(curve.values[0], [pd.value, -0.8], atol=1e-9)
    # a multiplier at -1 all along (to the Jacobian's accuracy on this stiff orbit); the
    # curve goes down in eta as k12 decreases
    assert np.all(np.abs(curve.multipliers[:, 0] + 1) < 1e-3)
    assert np.all(np.diff(curve.values[:, 0]) < 0)
    for j in (len(curve.values) // 3, 2 * len(curve.values) // 3, -1):
        eta_c, k12 = (float(v) for v in curve.values[j])
        _, pd_k = _period_doubling(eta_c + 1e-4, k12, curve.points[j], eta_c - 1e-4, eta_c + 1e-4)
        assert abs(pd_k.value - eta_c) < 1e-8, (k12, pd_k.value, eta_c)


def test_a_fold_curve_that_meets_a_grazing_of_the_section_ends_there():
    # Fig. 6's upper period-1 fold followed down in v_b (data/curves, made by
    # scripts/fold_curves_eta_vb.py) ends "step-too-small" at (4.0034, 0.0092064): there
    # dx1 has an extremum at zero (-2.6e-8; 1.4e-4 twenty points earlier), the orbit
    # grazes the section and the return map is no longer smooth. Resumed five points
    # before that end, the curve stops at the same place and names it.
    import os

    from stickslip_fast.bifurcation.stickphases import section_graze_margin

    stored = ssf.Curve.from_hdf5(os.path.join(os.path.dirname(__file__), "..", "data",
                                              "curves", "p1_fold_upper_down_eta_vb.h5"))  # fmt: skip
    i = len(stored.values) - 5
    (eta, vb), z = (float(v) for v in stored.values[i]), stored.points[i]
    branch = ssf.Branch(stored.system.replace(eta=eta, vb=vb), "eta", 1, np.array([eta]),
                        z[None, :], np.full(1, np.nan), np.full((1, 3), np.nan, complex),
                        np.zeros(1, bool))  # fmt: skip
    fold = ssf.Bifurcation("fold", eta, 0, z.copy())
    curve = ssf.continue_bifurcation(branch, fold, "vb", (0.0025, 0.04), direction=-1,
                                     ds=1e-4, ds_min=1e-12, max_points=40,
                                     stick_events=False)  # fmt: skip
    assert curve.status == "step-too-small"
    graze = [c for c in curve.codim2 if c.kind == "section-grazing"]
    assert len(graze) == 1 and graze[0].index == len(curve.values) - 1, curve.codim2
    np.testing.assert_allclose(graze[0].values, [4.0034242, 0.0092064], atol=2e-6)
    # the margin shrinks along the stored curve: 1.7e-3 of max |dx1| at its point 160
    # (0.02 in eta before the end), below GRAZE_TOL = 1e-5 only at the end
    (eta_a, vb_a), z_a = stored.values[160], stored.points[160]
    s_a = stored.system.replace(eta=float(eta_a), vb=float(vb_a))
    assert section_graze_margin(s_a, z_a, float(stored.T[160])) > 1e-3
