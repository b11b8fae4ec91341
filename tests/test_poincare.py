"""Poincare detection, period detection and classification of equilibria."""

import numpy as np
import pytest

import stickslip_fast as ssf
from stickslip_fast.core.poincare import detect_period


def test_symmetric_system_keeps_phi_identically_zero():
    # k12 = 0, phi = dphi = 0: M_s is proportional to dphi, so phi never moves
    for drive in ("constant", "dc-motor"):
        s = ssf.System.preset("symmetric", eta=5.0, drive=drive)
        r = ssf.simulate(s, 300.0, sample_dt=0.5)
        assert r.status == "ok"
        assert np.all(r.y[:, 2] == 0.0) and np.all(r.y[:, 3] == 0.0)
        assert np.all(r.column("phi1") == 0.0)
        assert np.abs(r.y[:, 0]).max() > 0.1  # while x does stick-slip


def test_points_are_exact_local_minima_of_x1():
    # eta = 2.0: the period-1 orbit (at eta = 4.0, used before, the motion is a
    # transient that has died out by t = 200: steady sliding, judged on the tail)
    s = ssf.System.preset("asymmetric", eta=2.0)
    r = ssf.simulate(s, 400.0, 100.0, sample_dt=1e-3)
    assert r.status == "ok" and len(r.t_poincare) > 5
    assert np.all(np.diff(r.t_poincare) > 0) and r.t_poincare[0] >= 100.0
    # dx1 = 0 at the crossing, to round-off of the dense output
    assert np.abs(r.column("dx1")).max() < 1e-13
    # each point's x1 is the minimum of the sampled x1 nearby
    for tp, xp in zip(r.t_poincare, r.column("x1")):
        near = np.abs(r.t - tp) < 0.2
        assert xp <= r.y[near, 0].min() + 1e-12
        # and dx1 goes from negative to positive across it
        i = np.searchsorted(r.t, tp)
        assert r.y[i - 1, 1] < 0 <= r.y[i + 1, 1]


def test_max_points_keeps_the_most_recent_points_in_order():
    s = ssf.System.preset("asymmetric", eta=9.99)
    full = ssf.simulate(s, 1500.0, 500.0)
    few = ssf.simulate(s, 1500.0, 500.0, max_points=5)
    none = ssf.simulate(s, 1500.0, 500.0, max_points=0)
    assert full.n_crossings == few.n_crossings == none.n_crossings == len(full.t_poincare)
    np.testing.assert_array_equal(few.poincare, full.poincare[-5:])
    np.testing.assert_array_equal(few.t_poincare, full.t_poincare[-5:])
    assert none.poincare.shape == (0, 4)


def test_strongly_damped_disk_is_steady_sliding_equilibrium():
    # c = 20 (overdamped): the disk settles at rest while the belt slides under it
    s = ssf.System.preset("asymmetric", c=20.0, eta=3.0)
    r = ssf.simulate(s, 2000.0, 1000.0)
    assert r.status == "equilibrium" and r.period == 0 and r.poincare.shape[0] == 0
    # the equilibrium of the steady slide: K q = -mu (T_s, M_s)(-v_b, 0) = (mu, 0)
    q = np.linalg.solve([[1.0, s.k12], [s.k12, 1.0]], [s.mu, 0.0])
    np.testing.assert_allclose(r.final_state[[0, 2]], q, rtol=1e-6)
    assert np.abs(r.final_state[[1, 3]]).max() < 1e-9


@pytest.mark.parametrize("n_osc", [1, 2])
def test_motor_too_weak_for_static_friction_stalls(n_osc):
    # v_b0 / beta = 1.12 < eta = 3: the motor cannot overcome the static friction
    s = ssf.System.preset("asymmetric", drive="dc-motor", beta=0.01, eta=3.0, n_oscillators=n_osc)
    r = ssf.simulate(s, 2000.0, 1000.0)
    assert r.status == "stalled" and r.poincare.shape[0] == 0
    assert abs(r.final_state[-1]) < 1e-2 * s.vb0
    # a strong motor on the same disks is not stalled
    ok = ssf.simulate(s.replace(beta=0.0014, eta=1.5), 2000.0, 1000.0)
    assert ok.status == "ok" and ok.period >= 1


def test_no_crossings_when_window_has_no_minimum():
    # the first stick phase of the literature set lasts > 20 time units
    r = ssf.simulate(ssf.System.preset("literature"), 20.0, 10.0)
    assert r.status == "no-crossings" and r.n_crossings == 0


def test_nonfinite_initial_state_is_refused_and_runaway_flagged():
    # c = -5 (negative damping) makes the motion grow without bound
    s = ssf.System.preset("asymmetric", c=-5.0)
    r = ssf.simulate(s, 1e4, y0=[1.0, 0.0, 0.0, 0.0])
    assert r.status in ("nonfinite", "step-underflow")
    r = ssf.simulate(ssf.System(), 100.0, max_steps=10)
    assert r.status == "max-steps" and r.n_steps == 10


@pytest.mark.parametrize("period", [1, 2, 3, 7, 11, 28, 64])
def test_detect_period_on_constructed_sequences(period):
    rng = np.random.default_rng(period)
    cycle = rng.normal(size=(period, 4))
    pts = np.array([cycle[j % period] for j in range(2 * period + 5)])
    pts += rng.normal(scale=1e-9, size=pts.shape)  # noise well below the tolerance
    assert detect_period(pts, len(pts), 1e-6, 64) == period
    # too few points to see two full cycles: no period
    assert detect_period(pts[: 2 * period - 1], 2 * period - 1, 1e-6, 64) == 0 or period == 1
    # noise above the tolerance: no period
    noisy = pts + rng.normal(scale=1e-3, size=pts.shape)
    assert detect_period(noisy, len(noisy), 1e-6, 64) == 0


def test_period_of_the_papers_examples():
    # paper: period-11 at eta = 2.7 (literature set, Fig. 3), period-2 at 9.99 (Fig. 7)
    lit = ssf.simulate(ssf.System.preset("literature", eta=2.7), 20000.0, 10000.0)
    assert lit.status == "ok" and lit.period == 11
    asym = ssf.simulate(ssf.System.preset("asymmetric", eta=9.99), 3000.0, 2000.0)
    assert asym.status == "ok" and asym.period == 2
    sym = ssf.simulate(ssf.System.preset("symmetric", eta=9.95), 3000.0, 2000.0)
    assert sym.status == "ok" and sym.period == 1


def _approach(rho: float, d_last: float, n: int = 40) -> np.ndarray:
    """n points of 4 equal coordinates approaching 1 geometrically (ratio rho per step),
    the last step being d_last; rho = 1: a steady drift of d_last per step."""
    k = np.arange(n)[::-1]  # steps still to come after each point, up to the last
    if rho == 1.0:
        x = 1.0 - d_last * k
    else:  # distance still to go: d_last rho / (1 - rho) after the last point
        x = 1.0 - d_last * rho / (1.0 - rho) / rho**k
    return np.ascontiguousarray(np.repeat(x[:, None], 4, axis=1))


@pytest.mark.parametrize(
    ("rho", "d_last", "expected"),
    [
        (0.8, 2e-6, 1),  # still to move: 8e-6, within tol x 2 = 2e-5
        (0.95, 2e-6, 0),  # still to move: 3.8e-5: the points drift on
        (1.0, 2e-6, 0),  # a steady drift: not contracting
        (0.95, 1e-12, 1),  # changes at noise level: the ratio says nothing
    ],
)
def test_ring_period_refuses_points_that_still_drift(rho, d_last, expected):
    # Each of the last 8 changes is within the period tolerance (1e-5 x (1 + 1)) in
    # every case; what differs is the change still to come, d rho / (1 - rho).
    from stickslip_fast.core.poincare import ring_period

    pts = _approach(rho, d_last)
    steps = np.abs(np.diff(pts[:, 0]))
    assert steps[-1] == pytest.approx(d_last, rel=1e-6, abs=1e-15)
    assert steps[-9:].max() <= 2e-5
    assert ring_period(pts, len(pts), 1e-5, 8, 3, 8) == expected
