"""Observed orders of convergence against an independent SciPy reference."""

import os
import sys

import numpy as np
import pytest
from scipy.integrate import solve_ivp

import stickslip_fast as ssf

sys.path.insert(0, os.path.join(os.path.dirname(__file__), "reference"))
import scipy_model  # noqa: E402  (independent NumPy implementation of the model)

T_END = 8.0


def _smooth_problem(drive):
    # eps = 0.5 makes the friction law smooth and non-stiff: a clean order test
    s = ssf.System.preset("asymmetric", eps=0.5, eta=3.0, c=0.05, drive=drive)
    y0 = [0.1, 0.0, -0.05, 0.02] + ([0.005] if drive == "dc-motor" else [])
    ref = solve_ivp(
        scipy_model.rhs, (0, T_END), y0, method="DOP853", rtol=1e-13, atol=1e-15,
        args=(s.to_dict(),),
    ).y[:, -1]  # fmt: skip
    return s, y0, ref


@pytest.mark.parametrize("drive", ["constant", "dc-motor"])
@pytest.mark.parametrize(
    "method,ns", [("dopri5-fixed", [40, 80, 160]), ("rodas5p", [40, 80, 160, 320])]
)
def test_fixed_step_order(drive, method, ns):
    s, y0, ref = _smooth_problem(drive)
    hs = np.array([T_END / n for n in ns])
    errs = np.array(
        [np.abs(ssf.simulate(s, T_END, y0=y0, method=method, h=h, max_points=0).final_state - ref).max()
         for h in hs]
    )  # fmt: skip
    order = np.polyfit(np.log(hs), np.log(errs), 1)[0]
    assert abs(order - 5.0) <= 0.3, (order, errs)


@pytest.mark.parametrize("drive", ["constant", "dc-motor"])
@pytest.mark.parametrize("method", ["dopri5", "rodas5p"])
def test_adaptive_order_from_work_precision(drive, method):
    # error ~ n_steps^(-order) for a well-controlled adaptive method
    s, y0, ref = _smooth_problem(drive)
    steps, errs = [], []
    for rtol in (1e-6, 1e-7, 1e-8, 1e-9, 1e-10):
        r = ssf.simulate(s, T_END, y0=y0, method=method, rtol=rtol, atol=rtol * 1e-2, max_points=0)
        steps.append(r.n_steps)
        errs.append(np.abs(r.final_state - ref).max())
    order = -np.polyfit(np.log(steps), np.log(errs), 1)[0]
    assert abs(order - 5.0) <= 0.3, (order, steps, errs)
    # and the tolerance is honoured: error within 10x rtol * |y|
    assert errs[-1] < 10 * 1e-10


def test_dense_output_and_sampling_match_reference():
    # the uniform grid comes from the dense output: compare it with SciPy's
    s, y0, _ = _smooth_problem("dc-motor")
    ts = np.linspace(0, T_END, 81)
    ref = solve_ivp(
        scipy_model.rhs, (0, T_END), y0, method="DOP853", rtol=1e-13, atol=1e-15,
        t_eval=ts, args=(s.to_dict(),),
    ).y.T  # fmt: skip
    for method in ("rodas5p", "dopri5"):
        r = ssf.simulate(s, T_END, y0=y0, method=method, rtol=1e-10, atol=1e-12, sample_dt=0.1)
        assert r.y.shape == (81, 5)
        np.testing.assert_allclose(r.t, ts, atol=1e-12)
        assert np.abs(r.y - ref).max() < 1e-8


def test_sticking_is_stiff_rodas5p_is_not_stability_limited():
    # Literature set: while the disk sticks |lambda| ~ mu (1 + eta') / eps ~ 2e6.
    s = ssf.System.preset("literature", eta=2.7)
    ref = solve_ivp(
        scipy_model.rhs, (0, 100.0), np.zeros(4), method="Radau", rtol=1e-10, atol=1e-13,
        args=(s.to_dict(),),
    ).y[:, -1]  # fmt: skip
    r = ssf.simulate(s, 100.0, max_points=0)
    assert r.n_steps < 2000
    np.testing.assert_allclose(r.final_state, ref, rtol=0, atol=5e-5 * np.abs(ref).max())
    # the explicit method is held to tiny steps by stability alone
    e = ssf.simulate(s, 100.0, method="dopri5", max_steps=200 * r.n_steps, max_points=0)
    assert e.status == "max-steps" and e.t_final < 30.0
