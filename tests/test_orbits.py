"""Periodic orbits (Newton on the Poincare map), Floquet multipliers and equilibria (issue 10).

References: a brute-force simulation at tight tolerance; finite differences of the engine's
own return map; an independent SciPy-only shooting code (tests/reference/scipy_shooting.py,
stored in orbit_reference.json); the analytic return map of a linear oscillator; the
independent NumPy model's Jacobian (tests/reference/scipy_model.py). About 15 s warm.
"""

from __future__ import annotations

import dataclasses
import json
import sys
from pathlib import Path

import numpy as np
import pytest

import stickslip_fast as ssf
from stickslip_fast.bifurcation.orbits import return_map
from stickslip_fast.model.params import P_ETA

REF = Path(__file__).resolve().parent / "reference"
sys.path.insert(0, str(REF))

import scipy_model  # noqa: E402

SECTION = [0, 2, 3]  # section coordinates of one disk on a constant belt (all but dx1)


@pytest.fixture(scope="module")
def converged():
    """Converged simulations from rest: eta = 2.0 (period 1) and eta = 9.99 (period 2)."""
    out = {}
    for eta in (2.0, 9.99):
        s = ssf.System.preset("asymmetric", eta=eta)
        out[eta] = (s, ssf.simulate(s, 20000, stop="converged"))
    return out


@pytest.fixture(scope="module")
def orbits(converged):
    return {eta: ssf.find_orbit(s, r) for eta, (s, r) in converged.items()}


@pytest.mark.parametrize("eta, period", [(2.0, 1), (9.99, 2)])
def test_orbit_reproduces_brute_force(converged, orbits, eta, period):
    s, r = converged[eta]
    assert r.period == period
    o = orbits[eta]
    assert o.converged and o.status == "converged" and o.period == period
    assert o.residual <= 1e-10
    assert o.stable
    # brute force: 30 more periods at tight tolerance from the converged state
    b = ssf.simulate(s, 30 * o.T, y0=r.final_state, rtol=1e-12, atol=1e-14)
    k = int(np.argmin(b.poincare[-period:, 0]))
    bf = np.roll(b.poincare[-period:], -k, axis=0)  # start at the smallest x1
    np.testing.assert_allclose(o.points, bf, rtol=0, atol=1e-8)
    assert o.points[0, 0] == o.points[:, 0].min()
    # dt[j]: time of arrival at the j-th of the last points; from the orbit's point i the next
    # crossing is point k + i + 1 of those
    dt = np.diff(b.t_poincare[-period - 1 :])
    assert abs(o.T - dt.sum()) < 1e-6
    np.testing.assert_allclose(np.diff(np.r_[0.0, o.times]), np.roll(dt, -(k + 1)), atol=1e-6)


@pytest.mark.parametrize("eta, period", [(2.0, 1), (9.99, 2)])
def test_multipliers_match_finite_differences_of_the_return_map(orbits, eta, period):
    o = orbits[eta]
    s = o.system
    z = o.points[0]
    h = 1e-6
    fd = np.empty((3, 3))
    for c, i in enumerate(SECTION):
        zp, zm = z.copy(), z.copy()
        zp[i] += h
        zm[i] -= h
        st_p, pp, _, _ = return_map(s, zp, period, tangents=False)
        st_m, pm, _, _ = return_map(s, zm, period, tangents=False)
        assert st_p == st_m == "ok"
        fd[:, c] = (pp[-1][SECTION] - pm[-1][SECTION]) / (2 * h)
    np.testing.assert_allclose(o.jacobian, fd, rtol=0, atol=1e-5)
    lead_fd = np.linalg.eigvals(fd)[np.argmax(np.abs(np.linalg.eigvals(fd)))]
    assert abs(o.multipliers[0] - lead_fd) < 1e-5
    # the multipliers are the Jacobian's eigenvalues, largest modulus first
    assert np.all(np.diff(np.abs(o.multipliers)) <= 0)


@pytest.mark.parametrize("eta, period", [(2.0, 1), (9.99, 2)])
@pytest.mark.parametrize("param, h", [("eta", 1e-6), ("vb", 1e-7), ("eps", 1e-10)])
def test_parameter_column_matches_finite_differences_of_the_return_map(orbits, eta, period,
                                                                       param, h):  # fmt: skip
    # dP^p/dparam from the sensitivity integrated with the tangents, against a central
    # difference of the map itself. vb and eps act through the friction law's slip speed:
    # with the old step (1e-7, 1 % of eps) dP/dvb at eta = 2 had the wrong sign
    o = orbits[eta]
    s = o.system
    z = o.points[0]
    st, _, _, jac = return_map(s, z, period, param=param)
    assert st == "ok" and jac.shape == (3, 4)
    np.testing.assert_allclose(jac[:, :3], o.jacobian, rtol=0, atol=1e-6)
    images = []
    for d in (h, -h):
        moved = dataclasses.replace(s, **{param: getattr(s, param) + d})
        st_d, pd, _, _ = return_map(moved, z, period, tangents=False)
        assert st_d == "ok"
        images.append(pd[-1][SECTION])
    fd = (images[0] - images[1]) / (2 * h)
    assert np.max(np.abs(fd)) > 1e-3
    np.testing.assert_allclose(jac[:, 3], fd, rtol=0, atol=1e-5 * max(1.0, np.max(np.abs(fd))))


def test_parameter_sensitivity_is_one_sided_at_the_valid_range_edge():
    from stickslip_fast.bifurcation.orbits import _sensitivity_params

    s = ssf.System.preset("asymmetric", eta=10.0)
    rows, inv = _sensitivity_params(s, "eta", 1e-7)
    # eta = 10 is the top of eta's valid range: the step goes down only
    assert np.array_equal(rows[0], s.to_array())
    assert rows[1][P_ETA] == pytest.approx(10.0 - 1e-6, abs=1e-15)
    assert inv == pytest.approx(1e6, rel=1e-9)
    with pytest.raises(ValueError, match="param"):
        return_map(s, np.zeros(4), 1, param="nope")


def test_finding_and_continuing_an_orbit_share_one_compiled_kernel(orbits):
    # issue 30: two variational kernels (plain tangents for find_orbit, tangents with
    # the parameter sensitivity for continue_orbit) compiled for ~17 and ~19 s on a
    # fresh install; now find_orbit runs the sensitivity kernel with the sensitivity
    # off, and continuing the orbit it found compiles nothing more
    from numba.core.dispatcher import Dispatcher

    from stickslip_fast.core import variational

    assert not isinstance(variational.propagate_tangents, Dispatcher)
    found = set(variational.propagate_sensitivity.signatures)
    assert found  # find_orbit (the fixture) ran it
    branch = ssf.continue_orbit(orbits[2.0], "eta", (2.0, 2.02), ds=0.01, max_points=3)
    assert len(branch.points) >= 2
    assert set(variational.propagate_sensitivity.signatures) == found


def test_leading_multiplier_at_eta_2_is_the_issue_value(orbits):
    # issue 10: independent shooting gives -0.0969, ~1e-8, ~2e-11
    m = orbits[2.0].multipliers
    assert abs(m[0] - (-0.0969)) < 5e-4
    assert np.all(np.abs(m[1:]) < 1e-6)


@pytest.mark.parametrize("case", json.loads((REF / "orbit_reference.json").read_text()))
def test_orbit_matches_independent_scipy_shooting(case):
    p = {k: v for k, v in case["params"].items()}
    s = ssf.System.from_dict(p)
    period = case["period"]
    ref_point = np.array(case["point"])
    # start where the SciPy code started: its brute-force point, x1 moved by 1e-4
    start = ref_point.copy()
    start[0] += case["start_offset_x1"]
    o = ssf.find_orbit(s, start, period)
    assert o.converged and o.residual <= 1e-10 and o.iterations >= 1
    # the SciPy point is one of the orbit's crossings
    d = np.min(np.max(np.abs(o.points - ref_point), axis=1))
    assert d < 1e-8
    assert abs(o.T - case["T"]) < 1e-6
    ref_mult = np.array(case["multipliers_real"]) + 1j * np.array(case["multipliers_imag"])
    assert abs(o.multipliers[0] - ref_mult[0]) < 1e-5


def test_dc_motor_orbit_reproduces_brute_force():
    s = ssf.System.preset("asymmetric", drive="dc-motor", eta=1.5)
    r = ssf.simulate(s, 20000, stop="converged")
    o = ssf.find_orbit(s, r)
    assert o.converged and o.period == r.period == 1 and o.residual <= 1e-10 and o.stable
    b = ssf.simulate(s, 30 * o.T, y0=r.final_state, rtol=1e-12, atol=1e-14)
    np.testing.assert_allclose(o.points[0], b.poincare[-1], rtol=0, atol=1e-8)
    assert o.multipliers.shape == (4,)


def test_unstable_multiplier_matches_brute_force_growth():
    # Two identical disks on one DC motor, started from rest, stay synchronised (x1 = x2, ...):
    # brute force converges to a period-2 orbit inside that invariant subspace, which is
    # unstable across it. An antisymmetric perturbation of 1e-11 grows by the leading
    # multiplier per period, measured here from the simulated Poincare points.
    s = ssf.System.preset("asymmetric", drive="dc-motor", eta=8.0, n_oscillators=2)
    r = ssf.simulate(s, 20000, stop="converged")
    o = ssf.find_orbit(s, r)
    assert o.converged and o.period == 2 and o.residual <= 1e-10
    assert not o.stable and o.multipliers[0].real > 2.0
    y0 = o.points[0].copy()
    y0[0] += 1e-11
    y0[4] -= 1e-11
    b = ssf.simulate(s, 20 * o.T, y0=y0, rtol=1e-12, atol=1e-14, max_points=100)
    d = np.abs(b.poincare[:, 0] - b.poincare[:, 4])
    growth = np.median(d[16:25] / d[14:23])  # linear regime, the stable directions decayed
    assert abs(o.multipliers[0] - growth) < 2e-4


def test_linear_oscillator_return_map_is_analytic():
    # mu = 0, no coupling: x'' + c x' + x = 0 and m phi'' + c phi' + phi = 0. From a minimum of
    # x the next one is T = 2 pi / w_d later, x -> x exp(-c T / 2), and (phi, dphi) moves by the
    # flow of its own oscillator: multipliers exp(-c T / 2) and exp(lambda_phi T).
    c, m = 0.05, 2.0
    s = ssf.System(mu=0.0, k12=0.0, c12=0.0, c=c, m=m)
    z = np.array([-0.1, 0.0, 0.05, 0.01])
    st, pts, times, jac = return_map(s, z, 1)
    assert st == "ok"
    T = 2 * np.pi / np.sqrt(1 - c * c / 4)
    assert abs(times[0] - T) < 1e-8
    assert abs(pts[0, 0] - (-0.1 * np.exp(-c * T / 2))) < 1e-10
    lam_phi = (-c + 1j * np.sqrt(4 * m - c * c)) / (2 * m)
    expected = np.sort_complex(np.array([np.exp(-c * T / 2), np.exp(lam_phi * T), np.exp(np.conj(lam_phi) * T)]))  # fmt: skip
    np.testing.assert_allclose(np.sort_complex(np.linalg.eigvals(jac)), expected, atol=1e-8)


def test_failures_are_reported_never_silent(converged):
    s, r = converged[2.0]
    start = r.poincare[-1].copy()
    start[0] += 1e-3
    o = ssf.find_orbit(s, start, 1, max_iter=0)
    assert (o.status, o.converged, o.stable) == ("max-iter", False, False)
    assert o.residual > 1e-10
    # asking for period 2 on the period-1 orbit: a fixed point, but not of the period asked
    o2 = ssf.find_orbit(s, r, 2)
    assert o2.status == "lower-period" and not o2.converged and not o2.stable
    # near the stable sliding equilibrium the map contracts onto it: a fixed point, not an orbit
    eq = ssf.find_equilibrium(s)
    o4 = ssf.find_orbit(s, eq.state + [-1e-4, 0.0, 0.0, 0.0], 1)
    assert o4.status == "equilibrium" and not o4.converged and not o4.stable
    # no crossing within t_max (a period is 9.6): the map cannot be evaluated
    o3 = ssf.find_orbit(s, r, 1, t_max=1.0)
    assert o3.status == "integration-failed" and not o3.converged and np.isnan(o3.T)


def test_census_attractor_as_start():
    s = ssf.System.preset("asymmetric", eta=9.99)
    c = ssf.census(s, "eta", [9.99], t_end=3000.0, stop="converged", n_starts=2, progress=False)
    att = [a for a in c.attractors[0] if a.kind == "orbit"][0]
    o = ssf.find_orbit(s, att)
    assert o.converged and o.period == att.period == 2
    np.testing.assert_allclose(o.points, att.points, rtol=0, atol=1e-6)
    rest = dataclasses.replace(att, kind="equilibrium", period=0)
    with pytest.raises(ValueError, match="start"):
        ssf.find_orbit(s, rest)


def test_period_detected_from_a_state():
    s = ssf.System.preset("asymmetric", eta=2.0)
    o = ssf.find_orbit(s, np.zeros(4))
    assert o.converged and o.period == 1
    assert abs(o.multipliers[0] - (-0.0969)) < 5e-4


def _ref_params(s):
    return {**s.to_dict(), "n_oscillators": s.n_oscillators}


@pytest.mark.parametrize(
    "overrides, start, kind",
    [
        ({}, "sliding", "sliding"),
        ({"drive": "dc-motor"}, "sliding", "sliding"),
        ({"drive": "dc-motor", "n_oscillators": 2}, "sliding", "sliding"),
        # with a stronger motor load the belt has a second rest point inside the stick band
        ({"drive": "dc-motor", "beta": 0.02}, "stall", "stall"),
    ],
)
def test_equilibrium_matches_reference_model(overrides, start, kind):
    s = ssf.System.preset("asymmetric", eta=2.0, **overrides)
    e = ssf.find_equilibrium(s, start)
    assert e.converged and e.kind == kind
    p = _ref_params(s)
    assert np.max(np.abs(scipy_model.rhs(0.0, e.state, p))) < 1e-12
    ref = np.linalg.eigvals(scipy_model.jac(0.0, e.state, p))
    np.testing.assert_allclose(np.sort_complex(e.eigenvalues), np.sort_complex(ref), rtol=1e-9, atol=1e-12)  # fmt: skip
    assert e.stable == bool(np.all(ref.real < 0))


def test_no_stall_is_reported_not_replaced_by_sliding():
    # the presets' motor (beta = 0.0014) has no rest point in the stick band
    s = ssf.System.preset("asymmetric", eta=2.0, drive="dc-motor")
    e = ssf.find_equilibrium(s, "stall")
    assert not e.converged and not e.stable


def test_bad_input_names_the_argument(converged):
    s, r = converged[2.0]
    for bad in (0, -1, 1.5, True):
        with pytest.raises(ValueError, match="period"):
            ssf.find_orbit(s, r, bad)
    with pytest.raises(ValueError, match="start"):
        ssf.find_orbit(s, np.array([np.nan, 0.0, 0.0, 0.0]), 1)
    with pytest.raises(ValueError, match="start"):
        ssf.find_orbit(s, np.zeros(5), 1)
    with pytest.raises(ValueError, match="start"):
        ssf.find_orbit(s.replace(eta=3.0), r)
    with pytest.raises(ValueError, match="tol"):
        ssf.find_orbit(s, r, tol=-1.0)
    with pytest.raises(ValueError, match="start"):
        ssf.find_equilibrium(s, [0.0, np.inf, 0.0, 0.0])
    with pytest.raises(ValueError, match="start"):
        ssf.find_equilibrium(s, "stall")  # constant belt
    with pytest.raises(ValueError, match="start"):
        ssf.find_equilibrium(s, "resting")


def _reference_stick_durations(s, point, T, threshold=100.0, n=20000):
    """The stick phases of one period from the independent SciPy model (Radau, rtol 1e-12)."""
    from scipy.integrate import solve_ivp

    p = _ref_params(s)
    dt = T / n
    t_eval = np.arange(n) * dt
    sol = solve_ivp(scipy_model.rhs, (0.0, T), point, method="Radau", t_eval=t_eval,
                    rtol=1e-12, atol=1e-14, args=(p,), jac=scipy_model.jac)  # fmt: skip
    speed = np.hypot(sol.y[1] - s.vb, sol.y[3])
    stick = speed < threshold * s.eps
    k0 = int(np.argmin(stick))
    st = np.roll(stick, -k0).astype(int)
    edges = np.flatnonzero(np.diff(np.r_[0, st, 0]))
    return (edges[1::2] - edges[::2]) * dt


@pytest.mark.parametrize("eta, count", [(2.0, 1), (9.99, 1)])
def test_stick_phases_match_the_reference_model(converged, eta, count):
    s, run = converged[eta]
    o = ssf.find_orbit(s, run)
    d = ssf.stick_phases(s, o.points[0], o.T)
    ref = _reference_stick_durations(s, o.points[0], o.T)
    assert d.size == ref.size == count
    # durations to two samples (T / 20000 each) against the independent integration
    np.testing.assert_allclose(np.sort(d), np.sort(ref), atol=2.5 * o.T / 20000)
    assert np.all(d > 0.05 * o.T)  # real stick phases, not flickers at the threshold


def test_stick_phases_on_an_uneven_multiple_shooting_mesh(converged):
    # Multiple shooting refines its mesh where a segment amplifies most, so its segments
    # differ in length. Sampled from the segment starts as if the cuts were even, the
    # P4 orbit at its period-doubling (2 stick phases) counted 19. Each segment is now
    # sampled over its own length: the count and durations are the one-trajectory ones.
    from stickslip_fast.bifurcation.multishoot import MultiShooting
    from stickslip_fast.bifurcation.multishoot_orbit import initial_segments

    s, run = converged[2.0]
    o = ssf.find_orbit(s, run)
    ref = ssf.stick_phases(s, o.points[0], o.T)
    mesh = np.array([0.0, 0.02, 0.05, 0.3, 0.31, 0.7, 1.0])
    status, starts = initial_segments(MultiShooting(s, mesh, 1e-11, 1e-13, 1e-13),
                                      o.points[0], o.T)  # fmt: skip
    assert status == "ok"
    d = ssf.stick_phases(s, starts[0], o.T, starts=starts, mesh=mesh)
    assert d.size == ref.size == 1
    np.testing.assert_allclose(d, ref, atol=2.5 * o.T / 20000)
    even = ssf.stick_phases(s, starts[0], o.T, starts=starts)  # the cuts taken as even
    assert not np.allclose(even.sum(), ref.sum(), atol=2.5 * o.T / 20000)
    with pytest.raises(ValueError, match="mesh"):
        ssf.stick_phases(s, starts[0], o.T, starts=starts, mesh=mesh[:-1])


def test_stick_phases_rejects_bad_input():
    s = ssf.System.preset("asymmetric", eta=2.0)
    with pytest.raises(ValueError, match="T"):
        ssf.stick_phases(s, np.zeros(4), -1.0)
    with pytest.raises(ValueError, match="point"):
        ssf.stick_phases(s, np.zeros(3), 1.0)
