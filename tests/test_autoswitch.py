"""method="auto": DOPRI5 while non-stiff, Rodas5P while stiff (stickslip_fast.core.autoswitch)."""

import numpy as np
import pytest
from numba import njit
from scipy.integrate import solve_ivp

import stickslip_fast as ssf
from stickslip_fast.core.autoswitch import AUTO_METHOD, _erk_dense_hermite
from stickslip_fast.core.steppers import DENSE_HERMITE, DENSE_POLY, dense_value
from stickslip_fast.core.testproblems import VanDerPol, solve_test_problem_auto


def _vdp_scipy(mu, y0, t_end):
    def f(t, y):
        return [y[1], mu * (1.0 - y[0] ** 2) * y[1] - y[0]]

    def jac(t, y):
        return [[0.0, 1.0], [-2.0 * mu * y[0] * y[1] - 1.0, mu * (1.0 - y[0] ** 2)]]

    method = "Radau" if mu > 10 else "DOP853"
    sol = solve_ivp(f, (0.0, t_end), y0, method=method, rtol=1e-12, atol=1e-12, jac=jac)
    assert sol.success
    return sol.y[:, -1]


def test_non_stiff_van_der_pol_stays_explicit_and_matches_scipy():
    y0 = np.array([2.0, 0.0])
    y, st, ns, nr, t, stats = solve_test_problem_auto(VanDerPol(1.0), y0, 20.0, 1e-10, 1e-12, 10**6)
    assert st == 0 and t == 20.0
    ref = _vdp_scipy(1.0, y0, 20.0)
    assert np.max(np.abs(y - ref)) < 1e-8
    to_stiff, to_explicit, steps_erk, steps_ros, tries_erk, tries_ros = stats
    # never stiff: DOPRI5 all the way
    assert to_stiff == 0 and to_explicit == 0 and steps_ros == 0 and steps_erk == ns
    assert tries_ros == 0 and tries_erk == ns + nr


def test_stiff_van_der_pol_switches_both_ways_and_matches_scipy():
    mu = 1000.0
    y0 = np.array([2.0, 0.0])
    t_end = 2500.0  # through two fast jumps, ending on a slow branch
    y, st, ns, nr, t, stats = solve_test_problem_auto(VanDerPol(mu), y0, t_end, 1e-10, 1e-12, 10**7)
    assert st == 0 and t == t_end
    ref = _vdp_scipy(mu, y0, t_end)
    assert abs(y[0] - ref[0]) < 1e-7 * abs(ref[0])
    assert abs(y[1] - ref[1]) < 1e-6 * max(1.0, abs(ref[1]))
    to_stiff, to_explicit, steps_erk, steps_ros, tries_erk, tries_ros = stats
    assert to_stiff >= 2 and to_explicit >= 1  # slow branch -> jump -> slow branch
    assert steps_erk > 0 and steps_ros > 0 and steps_erk + steps_ros == ns
    assert tries_erk >= steps_erk and tries_ros >= steps_ros and tries_erk + tries_ros == ns + nr
    # the stiff branches go to the Rosenbrock method: far fewer steps than DOPRI5 alone
    assert ns < 20_000


@njit(cache=True)
def _hermite_vs_poly(P, K, h, y0, y1, thetas):
    D_poly = np.empty((P.shape[0], K.shape[1]))
    for r in range(P.shape[0]):
        for i in range(K.shape[1]):
            acc = 0.0
            for j in range(P.shape[1]):
                acc += P[r, j] * K[j, i]
            D_poly[r, i] = h * acc
    D_herm = np.empty((P.shape[0] - 1, K.shape[1]))
    _erk_dense_hermite(P, K, h, D_herm)
    out = np.empty((thetas.size, 2, K.shape[1]))
    for k in range(thetas.size):
        for i in range(K.shape[1]):
            out[k, 0, i] = dense_value(DENSE_POLY, thetas[k], y0, y1, D_poly, i)
            out[k, 1, i] = dense_value(DENSE_HERMITE, thetas[k], y0, y1, D_herm, i)
    return out


def test_dopri5_dense_output_in_hermite_form_is_the_same_polynomial():
    rng = np.random.default_rng(1)
    P = AUTO_METHOD.erk.P
    K = rng.normal(size=(7, 3))
    h = 0.37
    y0 = rng.normal(size=3)
    y1 = y0 + h * (AUTO_METHOD.erk.b @ K)
    thetas = np.linspace(0.0, 1.0, 11)
    out = _hermite_vs_poly(P, K, h, y0, y1, thetas)
    np.testing.assert_allclose(out[:, 1], out[:, 0], rtol=0, atol=1e-14)


@pytest.fixture(scope="module")
def asymmetric_runs():
    system = ssf.System.preset("asymmetric", eta=2.0)
    kw = dict(rtol=1e-9, atol=1e-11, max_points=10_000)
    auto = ssf.simulate(system, 700.0, 400.0, method="auto", sample_dt=0.002, **kw)
    ros = ssf.simulate(system, 700.0, 400.0, method="rodas5p", sample_dt=0.002, **kw)
    tight = ssf.simulate(system, 700.0, 400.0, method="rodas5p", sample_dt=0.002,
                         rtol=1e-12, atol=1e-14, max_points=10_000)  # fmt: skip
    return auto, ros, tight


def test_auto_switches_both_ways_on_the_asymmetric_preset(asymmetric_runs):
    auto, ros, _ = asymmetric_runs
    sw = auto.switching
    assert ros.switching is None
    assert sw["to_stiff"] > 0 and sw["to_explicit"] > 0
    assert abs(sw["to_stiff"] - sw["to_explicit"]) <= 1
    assert sw["steps_explicit"] > 0 and sw["steps_rosenbrock"] > 0
    assert sw["steps_explicit"] + sw["steps_rosenbrock"] == auto.n_steps
    # every attempt is one method's: accepted or rejected
    assert sw["attempts_explicit"] + sw["attempts_rosenbrock"] == auto.n_steps + auto.n_rejected
    assert sw["attempts_explicit"] > sw["steps_explicit"]
    assert sw["attempts_rosenbrock"] > sw["steps_rosenbrock"]


def test_auto_poincare_points_equal_rodas5p_within_tolerance(asymmetric_runs):
    auto, ros, tight = asymmetric_runs
    assert auto.status == ros.status == "ok" and auto.period == ros.period
    assert len(auto.t_poincare) == len(ros.t_poincare) == len(tight.t_poincare) > 10
    # each within a tolerance-consistent bound of a tight run, and of each other
    err_auto = np.max(np.abs(auto.poincare - tight.poincare))
    err_ros = np.max(np.abs(ros.poincare - tight.poincare))
    assert err_auto < 1e-6 and err_ros < 1e-6
    assert np.max(np.abs(auto.poincare - ros.poincare)) < 2e-6
    # the return times (the phase drifts along the orbit, for every method)
    dt_auto, dt_tight = np.diff(auto.t_poincare), np.diff(tight.t_poincare)
    assert np.max(np.abs(dt_auto - dt_tight)) < 1e-6


def test_auto_samples_are_continuous_across_switches(asymmetric_runs):
    """The observer sees one continuous trajectory: uniform samples (dt = 0.002,
    several per step, so every step and every switch between the methods is
    sampled) agree with a tight run as well as Rodas5P's do at the same rtol, in
    value and in their first and second differences (an offset at a switch would
    show there as a jump of its own size)."""
    auto, ros, tight = asymmetric_runs
    assert auto.switching["to_stiff"] > 10  # many switches inside the sampled window
    assert auto.y.shape == ros.y.shape == tight.y.shape
    for k in (0, 1, 2):  # value, first and second differences
        e_auto = np.abs(np.diff(auto.y, k, axis=0) - np.diff(tight.y, k, axis=0)).max(axis=0)
        e_ros = np.abs(np.diff(ros.y, k, axis=0) - np.diff(tight.y, k, axis=0)).max(axis=0)
        # (the phase of the orbit drifts, ~2e-5 in time by t = 700, for both methods)
        assert np.all(e_auto < 5e-6)
        assert np.all(e_auto <= 1.5 * e_ros + 1e-9), (k, e_auto, e_ros)


def test_auto_labels_equal_rodas5p_over_a_sweep():
    system = ssf.System.preset("asymmetric")
    etas = np.array([1.5, 2.0, 2.7, 4.0, 6.0, 9.99])
    kw = dict(t_end=1500.0, t_transient=1000.0, max_points=64)
    a = ssf.sweep(system, "eta", etas, method="auto", **kw)
    r = ssf.sweep(system, "eta", etas, method="rodas5p", **kw)
    assert list(a.status) == list(r.status)
    assert np.array_equal(a.period, r.period)
    ok = np.asarray(a.status) == "ok"
    assert ok.sum() >= 3
    assert np.nanmax(np.abs(a.points[ok] - r.points[ok])) < 1e-5


def test_auto_on_two_disks_with_a_dc_motor_matches_rodas5p():
    """The generic (bordered) kernel: N = 2 on a DC motor."""
    system = ssf.System.preset("asymmetric", drive="dc-motor", n_oscillators=2, eta=1.5)
    kw = dict(rtol=1e-9, atol=1e-11)
    a = ssf.simulate(system, 600.0, 400.0, method="auto", **kw)
    r = ssf.simulate(system, 600.0, 400.0, method="rodas5p", **kw)
    assert a.status == r.status == "ok" and a.period == r.period
    assert len(a.t_poincare) == len(r.t_poincare) > 10
    assert np.max(np.abs(a.poincare - r.poincare)) < 1e-6
    assert a.switching["to_stiff"] > 0 and a.switching["to_explicit"] > 0


@pytest.mark.parametrize(
    "preset, eta, rtol",
    [("literature", 6.0, 1e-6), ("asymmetric", 9.99, 1e-5), ("symmetric", 9.0, 1e-5)],
)
def test_auto_does_not_chatter_in_the_stick_band(preset, eta, rtol):
    """Hairer's secant estimate missed the stick band's stiffness here: DOPRI5 chattered
    about the band with steps ~1e-4 and ran out of 2e7 steps (literature set: 6 s, where
    Rodas5P takes 1159 steps and 2 ms). The Jacobian probe and the busy count switch."""
    system = ssf.System.preset(preset, eta=eta)
    kw = dict(rtol=rtol, atol=0.01 * rtol, max_steps=200_000)
    a = ssf.simulate(system, 1000.0, 500.0, method="auto", **kw)
    r = ssf.simulate(system, 1000.0, 500.0, method="rodas5p", **kw)
    assert a.status == r.status == "ok"
    attempts = a.switching["attempts_explicit"] + a.switching["attempts_rosenbrock"]
    assert attempts < 20 * (r.n_steps + r.n_rejected)
    assert a.switching["to_stiff"] > 0


def test_auto_takes_the_rosenbrock_method_in_the_stick_band_from_the_start():
    """From rest on a moving belt the disk sticks at once (Jacobian eigenvalue ~ -1e5):
    at rtol 1e-5 the explicit method used to take 10^6 steps in the first 20 time units."""
    system = ssf.System.preset("asymmetric", eta=9.99)
    a = ssf.simulate(system, 20.0, rtol=1e-5, atol=1e-7, method="auto", max_steps=200_000)
    assert a.status != "max-steps"
    assert a.switching["steps_explicit"] < 1000
    assert a.switching["steps_rosenbrock"] > 0


def test_auto_does_not_switch_to_and_fro_every_few_steps():
    """A case of the classification corpus (literature set, two disks on a constant belt,
    eta = 9.88): disk 1 sticks (Jacobian radius ~1e7) while disk 2 slides fast. The stiff
    mode's calm test passed on its first, tiny steps and the probe switched back at once:
    2.5e5 switches each way and out of steps. A short explicit stretch now doubles the calm
    steps the next stiff stretch needs."""
    import classification_corpus as cc

    cases = cc.random_cases(100, 11, "literature")
    drive, n_osc, eta, y0 = next(c for c in cases if c[1] == 2 and abs(c[2] - 9.8836) < 1e-4)
    system = cc.system_of(drive, n_osc, "literature").replace(eta=eta)
    a = ssf.simulate(system, 800.0, y0=y0, method="auto", max_steps=200_000)
    r = ssf.simulate(system, 800.0, y0=y0, method="rodas5p")
    assert (a.status, a.period) == (r.status, r.period) == ("ok", 0)
    assert a.switching["to_stiff"] < 1000
    attempts = a.switching["attempts_explicit"] + a.switching["attempts_rosenbrock"]
    assert attempts < 3 * (r.n_steps + r.n_rejected)


def test_auto_settings():
    system = ssf.System.preset("asymmetric")
    with pytest.raises(ValueError, match="not used by 'auto'"):
        ssf.simulate(system, 10.0, method="auto", h=1e-3)
    assert "auto" in ssf.METHODS


def test_floor_benchmark_prices_each_method_attempt_at_its_bare_cost():
    """benchmarks/autoswitch_floor.py's floor: attempts x bare costs, against LSODA / goal."""
    from benchmarks import autoswitch_floor as floor_mod  # the repository root is on the path

    sw = dict(attempts_explicit=1000, attempts_rosenbrock=300, steps_explicit=900,
              steps_rosenbrock=200)  # fmt: skip
    matched = {"cases": {"c": {"targets": {
        "1e-06": dict(auto=dict(time=1.0e-3, switching=sw), peer=dict(time=2.4e-3)),
        "1e-08": dict(auto=dict(time=2.0e-3, switching=sw), peer=dict(time=3.0e-3)),
    }}}}  # fmt: skip
    bare = {"c": dict(explicit_attempt=200.0, rosenbrock_attempt=400.0, rosenbrock_accept=50.0)}
    f = floor_mod.floors(matched, bare)
    lo = f["c/1e-06"]
    # 1000 * 200 ns + 300 * 400 ns + 200 * 50 ns = 0.33 ms
    assert lo["floor"] == pytest.approx(0.33e-3, rel=1e-12)
    assert lo["budget"] == pytest.approx(0.8e-3) and lo["goal"] == 3.0
    assert lo["speedup_at_floor"] == pytest.approx(2.4 / 0.33)
    # accepted steps only: 900 * 200 + 200 * (400 + 50) ns = 0.27 ms
    assert lo["floor_no_rejections"] == pytest.approx(0.27e-3, rel=1e-12)
    hi = f["c/1e-08"]
    assert hi["goal"] == 2.0 and hi["auto_over_floor"] == pytest.approx(2 / 0.33)
