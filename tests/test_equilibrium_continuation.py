"""Continuation of equilibria (issue 10): folds and Hopf points against an independent reference.

The DC-motor drive of the asymmetric set (eta = 2, N = 1) with a growing motor load beta
has an S-shaped curve of rest points: steady sliding loses stability at a Hopf point,
turns at a fold, and comes back as an unstable branch that turns again into the stalled
belt. With the disks at rest, a rest point with belt speed v satisfies
vb0 - v - beta v B(v) = 0 (B from the friction law), so the folds in beta are the extrema
of beta(v) = (vb0 - v) / (v B(v)); the Hopf point is where the rightmost complex pair of
the Jacobian crosses the imaginary axis. Both are computed here from the independent
SciPy/NumPy model in tests/reference (scipy.optimize), not from the engine. About 3 s.
"""

from __future__ import annotations

import math
import sys
from pathlib import Path

import numpy as np
import pytest
from scipy.optimize import brentq, minimize_scalar

import stickslip_fast as ssf
from stickslip_fast.bifurcation.continuation import _equilibrium_tests, pseudo_arclength

sys.path.insert(0, str(Path(__file__).parent / "reference"))
import scipy_model  # noqa: E402

SYSTEM = ssf.System.preset("asymmetric", eta=2.0, drive="dc-motor")


def _ref(beta):
    return {**SYSTEM.replace(beta=beta).to_dict(), "n_oscillators": 1}


def _beta_of_v(v):
    p = _ref(SYSTEM.beta)
    ts, _ = scipy_model.friction(-v, 0.0, p["eps"], scipy_model.eta_prime(p["eta"]))
    return (p["vb0"] - v) / (-ts)


def _rest_state(v, beta):
    # disks at rest: x + k12 phi = -mu T_s(-v, 0), k12 x + phi = 0
    p = _ref(beta)
    ts, _ = scipy_model.friction(-v, 0.0, p["eps"], scipy_model.eta_prime(p["eta"]))
    x = -p["mu"] * ts / (1.0 - p["k12"] ** 2)
    return np.array([x, 0.0, -p["k12"] * x, 0.0, v])


def _hopf_test(beta, v_lo, v_hi):
    v = brentq(lambda u: _beta_of_v(u) - beta, v_lo, v_hi, xtol=1e-16)
    ev = np.linalg.eigvals(scipy_model.jac(0.0, _rest_state(v, beta), _ref(beta)))
    return ev[np.abs(ev.imag) > 1e-12].real.max()


@pytest.fixture(scope="module")
def branch():
    e = ssf.find_equilibrium(SYSTEM, "sliding")
    return e, ssf.continue_equilibrium(
        e, "beta", (0.0005, 0.05), ds=0.001, ds_max=0.005, max_points=400
    )


def test_folds_and_hopf_match_the_reference_model(branch):
    _, br = branch
    kinds = [b.kind for b in br.bifurcations]
    assert kinds == ["hopf", "fold", "fold"], br.summary()
    hopf, fold_hi, fold_lo = (b.value for b in br.bifurcations)
    # folds: the extrema of beta(v) of the reference friction law
    v_max = minimize_scalar(lambda v: -_beta_of_v(v), bracket=(5e-5, 8.5e-5, 2e-4), tol=1e-14)
    v_min = minimize_scalar(_beta_of_v, bracket=(3e-6, 6.8e-6, 2e-5), tol=1e-14)
    assert abs(fold_hi - _beta_of_v(v_max.x)) < 1e-10
    assert abs(fold_lo - _beta_of_v(v_min.x)) < 1e-10
    # the belt speed there is flat in beta (a fold): a 1e-11 error in beta allows ~1e-7 in v
    assert abs(br.bifurcations[1].point[-1] - v_max.x) < 1e-7
    # Hopf: the reference Jacobian's rightmost complex pair on the sliding root
    ref_hopf = brentq(lambda b: _hopf_test(b, v_max.x, 0.0112), 0.0108, 0.0111, xtol=1e-14)
    assert abs(hopf - ref_hopf) < 1e-9
    assert fold_lo < hopf < fold_hi


def test_branch_points_stability_and_eigenvalues(branch):
    e, br = branch
    assert br.period == 0 and np.all(np.isnan(br.T)) and br.values[0] == SYSTEM.beta
    np.testing.assert_array_equal(br.points[0], e.state)
    hopf = br.bifurcations[0].value
    # stable up to the Hopf point on the first (sliding) side, unstable after it
    before = br.values < hopf
    first = int(np.argmax(~before))
    assert br.stable[:first].all() and not br.stable[first:].any()
    for i in (0, first // 2, first + 3, len(br.values) - 2):
        p = _ref(float(br.values[i]))
        y = br.points[i]
        assert np.max(np.abs(scipy_model.rhs(0.0, y, p))) < 1e-11
        ref = np.linalg.eigvals(scipy_model.jac(0.0, y, p))
        np.testing.assert_allclose(np.sort_complex(br.multipliers[i]), np.sort_complex(ref),
                                   rtol=1e-7, atol=1e-10)  # fmt: skip


def test_sliding_on_a_constant_belt_is_stable_over_the_whole_range():
    # the census finds steady sliding at every eta of Fig. 6; the branch reaches both
    # ends of eta's valid range [1, 10] (one-sided differences there) without a bifurcation
    e = ssf.find_equilibrium(ssf.System.preset("asymmetric", eta=2.0), "sliding")
    for d in (1, -1):
        br = ssf.continue_equilibrium(e, "eta", (1.0, 10.0), ds=0.1, ds_max=0.5, direction=d)
        assert br.status == "bounds" and br.bifurcations == [] and br.stable.all()
        assert abs(br.values[-1] - (10.0 if d > 0 else 1.0)) < 1e-9


def test_hopf_normal_form_is_located():
    # x' = lam x - y, y' = x + lam y at the origin: eigenvalues lam +- i, Hopf at lam = 0
    def evaluate(x):
        lam = x[-1]
        J = np.array([[lam, -1.0], [1.0, lam]])
        G = J @ x[:2]
        return True, G, np.hstack([J, x[:2][::-1, None] * np.array([[1.0], [1.0]])]), J

    xs, eigs, bifs, status = pseudo_arclength(
        evaluate, np.array([0.0, 0.0, -0.5]), 1.0, (-0.5, 0.5), ds=0.07, ds_min=1e-9,
        ds_max=0.1, max_points=100, tol=1e-12, tests=_equilibrium_tests,
    )  # fmt: skip
    assert status == "bounds" and [b[0] for b in bifs] == ["hopf"]
    assert abs(bifs[0][1]) < 1e-9
    assert math.isclose(xs[-1][-1], 0.5)


def test_bad_input_names_the_argument(branch):
    e, _ = branch
    with pytest.raises(ValueError, match="equilibrium"):
        ssf.continue_equilibrium("sliding", "beta", (0.001, 0.02))
    with pytest.raises(ValueError, match="bounds"):
        ssf.continue_equilibrium(e, "beta", (0.002, 0.02))
    with pytest.raises(ValueError, match="param"):
        ssf.continue_equilibrium(e, "n_oscillators", (1, 3))
    with pytest.raises(ValueError, match="ds"):
        ssf.continue_equilibrium(e, "beta", (0.001, 0.02), ds=-1.0)


def test_cli_continues_an_equilibrium(branch, tmp_path, capsys):
    from stickslip_fast.bifurcation.continuation import Branch
    from stickslip_fast.cli import main

    _, br = branch
    cfg = tmp_path / "e.toml"
    cfg.write_text(
        '[system]\npreset = "asymmetric"\ndrive = "dc-motor"\neta = 2.0\n'
        '[continue]\nparam = "beta"\nbounds = [0.0005, 0.05]\nstart = "sliding"\n'
        "ds = 0.001\nds_max = 0.005\nmax_points = 400\n"
    )
    out = tmp_path / "e.h5"
    assert main(["continue", str(cfg), "-o", str(out), "--quiet"]) == 0
    got = Branch.from_hdf5(out)
    np.testing.assert_array_equal(got.values, br.values)
    assert got.period == 0 and [b.label for b in got.bifurcations] == ["H", "F", "F"]
    assert main(["info", str(out)]) == 0
    assert "hopf" in capsys.readouterr().out
    cfg.write_text('[continue]\nparam = "beta"\nbounds = [0.0005, 0.05]\nstart = "slide"\n')
    assert main(["continue", str(cfg), "-o", str(out)]) == 2
    assert "[continue].start" in capsys.readouterr().err


def test_both_directions_join_into_one_branch_through_the_start(tmp_path):
    from stickslip_fast.bifurcation.continuation import Branch, join_branches
    from stickslip_fast.cli import main

    e = ssf.find_equilibrium(SYSTEM, "sliding")
    kw = dict(ds=0.001, ds_max=0.005, max_points=400)
    down = ssf.continue_equilibrium(e, "beta", (0.0005, 0.05), direction=-1, **kw)
    up = ssf.continue_equilibrium(e, "beta", (0.0005, 0.05), direction=1, **kw)
    both = join_branches(down, up)
    n = down.values.size
    assert both.values.size == n + up.values.size - 1
    np.testing.assert_array_equal(both.values[: n - 1], down.values[:0:-1])
    np.testing.assert_array_equal(both.values[n - 1 :], up.values)
    assert both.values[0] == 0.0005 and down.status == "bounds"
    assert both.status == f"lower end: bounds; upper end: {up.status}"
    # the bifurcations keep their values and name the point just before them in the new order
    assert [b.kind for b in both.bifurcations] == ["hopf", "fold", "fold"]
    for b in both.bifurcations:
        j = b.index
        lo, hi = sorted(both.values[j : j + 2])
        assert lo - 1e-9 <= b.value <= hi + 1e-9 or b.kind == "fold"
    hopf = both.bifurcations[0]
    assert both.values[hopf.index] <= hopf.value <= both.values[hopf.index + 1]
    with pytest.raises(ValueError, match="one start"):
        join_branches(up, ssf.continue_equilibrium(
            ssf.find_equilibrium(SYSTEM.replace(beta=0.002), "sliding"), "beta", (0.0005, 0.05),
            **kw))  # fmt: skip
    # the CLI's direction = "both" writes the joined branch
    cfg = tmp_path / "e.toml"
    cfg.write_text(
        '[system]\npreset = "asymmetric"\ndrive = "dc-motor"\neta = 2.0\n'
        '[continue]\nparam = "beta"\nbounds = [0.0005, 0.05]\nstart = "sliding"\n'
        'direction = "both"\nds = 0.001\nds_max = 0.005\nmax_points = 400\n'
    )
    out = tmp_path / "both.h5"
    assert main(["continue", str(cfg), "-o", str(out), "--quiet"]) == 0
    got = Branch.from_hdf5(out)
    np.testing.assert_array_equal(got.values, both.values)
    assert [b.index for b in got.bifurcations] == [b.index for b in both.bifurcations]
