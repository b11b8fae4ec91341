"""Lyapunov exponent from the variational equations, and synchronization measures."""

import numpy as np
import pytest

from stickslip_fast import System
from stickslip_fast.analysis import (
    event_times,
    largest_lyapunov,
    phases_from_events,
    second_derivative_form,
    sync_error,
    tangent_rhs,
    wrap_phase,
)
from stickslip_fast.core.poincare import detect_period
from stickslip_fast.model.equations import (
    dense_jacobian,
    eta_prime,
    friction_partials,
    friction_second_partials,
)

# ------------------------------------------------------------ friction 2nd derivatives

_POINTS = [
    (3e-5, 1e-5),
    (-2e-5, 4e-6),
    (1e-6, -2e-5),
    (5e-3, 2e-3),
    (-0.03, 0.01),
    (7e-6, 0.0),
    (0.0, 9e-6),
]


@pytest.mark.parametrize("eta", [1.2, 2.7, 9.99])
@pytest.mark.parametrize("v,w", _POINTS)
def test_friction_second_partials_match_finite_differences(eta, v, w):
    eps, etap = 1e-5, eta_prime(eta)
    d = 1e-6 * max(abs(v), abs(w), eps)  # central differences of the first partials
    pv = np.array(friction_partials(v + d, w, eps, etap))
    mv = np.array(friction_partials(v - d, w, eps, etap))
    pw = np.array(friction_partials(v, w + d, eps, etap))
    mw = np.array(friction_partials(v, w - d, eps, etap))
    dv = (pv - mv) / (2 * d)  # d/dv of (T, M, T_v, T_w, M_v, M_w)
    dw = (pw - mw) / (2 * d)
    t_vv, t_vw, t_ww, m_vv, m_vw, m_ww = friction_second_partials(v, w, eps, etap)
    # from d/dv and d/dw of T_v, T_w, M_v, M_w: every mixed pair checked twice
    expect = {
        "T_vv": (t_vv, [dv[2]]),
        "T_vw": (t_vw, [dw[2], dv[3]]),
        "T_ww": (t_ww, [dw[3]]),
        "M_vv": (m_vv, [dv[4]]),
        "M_vw": (m_vw, [dw[4], dv[5]]),
        "M_ww": (m_ww, [dw[5]]),
    }
    scale = max(abs(x) for x in np.concatenate([dv[2:], dw[2:]]))
    for name, (got, fds) in expect.items():
        for fd in fds:
            assert got == pytest.approx(fd, rel=1e-6, abs=1e-7 * scale), name


def _random_state(system, rng):
    n = system.n_state
    y = rng.normal(scale=0.01, size=n)
    for i in range(system.n_oscillators):
        y[4 * i + 1] = rng.normal(scale=2e-5)  # near sticking: the stiff region
        y[4 * i + 3] = rng.normal(scale=2e-5)
    if system.is_dc_motor:
        y[-1] = 0.01
    return y


@pytest.mark.parametrize(
    "system",
    [
        System.preset("asymmetric", eta=9.99),
        System.preset("literature", eta=2.7, drive="dc-motor", n_oscillators=3),
    ],
)
def test_tangent_rhs_and_second_derivative_form(system):
    rng = np.random.default_rng(0)
    p = system.to_array()
    n_osc, dc = system.n_oscillators, system.is_dc_motor
    for _ in range(5):
        y = _random_state(system, rng)
        u = rng.normal(size=y.size)
        v = rng.normal(size=y.size)
        jac = dense_jacobian(y, p, n_osc, dc)
        fy = np.empty(y.size)
        fu = np.empty(y.size)
        tangent_rhs(y, u, p, n_osc, dc, fy, fu)
        np.testing.assert_allclose(fu, jac @ u, rtol=1e-12, atol=1e-12 * np.abs(jac @ u).max())
        # D^2 f(y)[u, v] = d/ds J(y + s v) u, central differences (relative step 1e-6)
        s = 1e-6 * 2e-5
        fd = dense_jacobian(y + s * v, p, n_osc, dc) - dense_jacobian(y - s * v, p, n_osc, dc)
        fd = fd @ u / (2 * s)
        out = np.empty(y.size)
        second_derivative_form(y, u, v, p, n_osc, dc, out)
        np.testing.assert_allclose(out, fd, rtol=1e-5, atol=1e-6 * np.abs(fd).max())
        out2 = np.empty(y.size)
        second_derivative_form(y, v, u, p, n_osc, dc, out2)
        np.testing.assert_allclose(out2, out, rtol=1e-12, atol=1e-12 * np.abs(out).max())


# ------------------------------------------------------------------------- Lyapunov


def test_lyapunov_damped_linear_oscillator():
    # mu = 0, k12 = 0: x'' + c x' + x = 0 and m phi'' + c phi' + phi = 0 decouple.
    # Eigenvalue real parts -c/2 = -0.1 (x) and -c/(2m) = -0.05 (phi, m = 2):
    # the largest exponent is -0.05.
    system = System(mu=0.0, k12=0.0, c=0.2, m=2.0)
    res = largest_lyapunov(system, 2000.0, 100.0, y0=[1.0, 0.0, 1.0, 0.0])
    assert res.status == "ok"
    assert res.exponent == pytest.approx(-0.05, abs=1e-3)
    assert res.exponent_fit == pytest.approx(-0.05, abs=1e-3)
    assert res.convergence.shape[1] == 2 and res.convergence[-1, 1] == pytest.approx(res.exponent)


@pytest.mark.parametrize(
    "preset,eta,period",
    [("asymmetric", 9.99, 2), ("symmetric", 5.0, 1)],
)
def test_lyapunov_periodic_stick_slip_orbit_is_zero(preset, eta, period):
    from stickslip_fast import simulate

    system = System.preset(preset, eta=eta)
    res = largest_lyapunov(system, 12000.0, 2000.0)
    assert res.status == "ok"
    assert abs(res.exponent) < 1e-3
    assert abs(res.exponent_fit) < 1e-4
    assert simulate(system, 12000.0, 2000.0).period == period


def test_lyapunov_rejects_bad_arguments():
    s = System()
    with pytest.raises(ValueError):
        largest_lyapunov(s, 10.0, 10.0)
    with pytest.raises(ValueError):
        largest_lyapunov(s, 10.0, 0.0, renorm_dt=0.0)
    with pytest.raises(ValueError):
        largest_lyapunov(s, 10.0, 0.0, u0=np.zeros(4))
    with pytest.raises(TypeError):
        largest_lyapunov("asymmetric", 10.0)


# ------------------------------------------------------------------ synchronization


def _signals(phases, t_end=200.0, dt=0.01, omega=1.0):
    """Engine-layout samples of N oscillators x_i = -cos(omega t + phase_i)."""
    t = np.arange(0.0, t_end, dt)
    cols = []
    for ph in phases:
        arg = omega * t + ph
        cols += [-np.cos(arg), omega * np.sin(arg), 0.1 * np.cos(arg), 0 * t]
    return t, np.column_stack(cols)


def test_event_times_are_minima_of_x():
    t, y = _signals([0.3])
    ev = event_times(t, y[:, 1])
    # minima of -cos(t + 0.3): t = 2 pi k - 0.3
    expect = 2 * np.pi * np.arange(1, ev.size + 1) - 0.3
    np.testing.assert_allclose(ev, expect, atol=1e-5)


def test_in_phase_identical_oscillators():
    t, y = _signals([0.0, 0.0])
    res = phases_from_events(t, y, 2)
    assert res.classification == "in-phase"
    assert res.labels == ["reference", "in-phase"]
    assert res.order_parameter == pytest.approx(1.0, abs=1e-9)
    assert np.abs(res.phase_diff).max() < 1e-9


def test_anti_phase_half_period_shift():
    t, y = _signals([0.0, np.pi])
    res = phases_from_events(t, y, 2)
    assert res.classification == "anti-phase"
    assert abs(wrap_phase(res.mean_diff[1] - np.pi)) < 1e-3
    assert res.order_parameter == pytest.approx(0.0, abs=1e-3)


def test_constant_offset_and_drift_are_desynchronized():
    t, y = _signals([0.0, np.pi / 2])
    res = phases_from_events(t, y, 2)
    assert res.classification == "desynchronized"
    assert res.mean_diff[1] == pytest.approx(np.pi / 2, abs=1e-3)
    # detuned second oscillator: the difference drifts through every value
    t, y1 = _signals([0.0])
    _, y2 = _signals([0.0], omega=1.1)
    res = phases_from_events(t, np.hstack([y1, y2]), 2)
    assert res.classification == "desynchronized"
    assert res.spread[1] > 2.0
    assert res.order_parameter < 0.9


def test_three_oscillators_mixed_and_wrap():
    t, y = _signals([0.0, 0.0, np.pi])
    res = phases_from_events(t, y, 3)
    assert res.labels == ["reference", "in-phase", "anti-phase"]
    assert res.classification == "mixed"
    assert res.order_parameter == pytest.approx(1 / 3, abs=1e-3)
    np.testing.assert_allclose(wrap_phase([np.pi, -np.pi, 3 * np.pi, 0.5]), [np.pi] * 3 + [0.5])


def test_sync_error_from_points():
    rng = np.random.default_rng(3)
    disk = rng.normal(size=(10, 4))
    same = np.hstack([disk, disk, np.full((10, 1), 0.01)])  # DC-motor layout
    assert sync_error(same, 2) == 0.0
    other = disk + np.array([3.0, 4.0, 0.0, 0.0])  # distance 5 at every point
    assert sync_error(np.hstack([disk, other]), 2) == pytest.approx(5.0)
    padded = np.vstack([np.hstack([disk, other]), np.full((3, 8), np.nan)])
    assert sync_error(padded, 2) == pytest.approx(5.0)
    assert sync_error(disk, 1) == 0.0


def test_period_three_sequence_of_points():
    base = np.array([[0.1, 0.0, 0.2, 0.3], [-0.2, 0.0, 0.1, 0.0], [0.05, 0.0, -0.3, 0.1]])
    pts = np.tile(base, (7, 1))
    assert detect_period(pts, pts.shape[0], 1e-9, 64) == 3
    # points of two in-phase disks: period 3 and zero sync error
    two = np.hstack([pts, pts])
    assert detect_period(two, two.shape[0], 1e-9, 64) == 3
    assert sync_error(two, 2) == 0.0
