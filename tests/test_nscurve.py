"""Two-parameter continuation of Neimark-Sacker points (issue 28, item 2) on a map whose NS
curve and angle are known in closed form.

(x, y, w) -> (y, b y - a x + x^2 + 1, (0.3 + 0.1 x) w): the fixed point x = y = s, w = 0
has the multipliers of [[0, 1], [2 s - a, b]] (determinant a - 2 s, trace b) and
0.3 + 0.1 s. An NS point (determinant 1) has s = (a - 1) / 2, and s^2 + (b - a - 1) s + 1
= 0 gives the curve a = b - 1 + sqrt((b - 2)^2 + 4), |b| < 2, with angle theta =
arccos(b / 2): the 1:1 resonance at (a, b) = (3, 2), 1:4 at (2 sqrt 2 - 1, 0), 1:3 at
(sqrt 13 - 2, -1) and 1:2 at (2 sqrt 5 - 3, -2).
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from turning_forms import plane_turn

from stickslip_fast.bifurcation.arclength import pseudo_arclength
from stickslip_fast.bifurcation.nscurve import follow_ns_curve

KW = dict(ds=0.02, ds_min=1e-8, ds_max=0.05, max_points=400, tol=1e-12)


def family(x):
    u, v, w, a, b = x
    A = np.array([[0.0, 1.0, 0.0], [2 * u - a, b, 0.0], [0.1 * w, 0.0, 0.3 + 0.1 * u]])
    G = np.array([v - u, b * v - a * u + u * u + 1 - v, (0.3 + 0.1 * u) * w - w])
    dp = np.array([[0.0, 0.0], [-u, v], [0.0, 0.0]])
    return True, G, np.hstack([A - np.eye(3), dp]), A


def a_ns(b):
    return b - 1 + np.sqrt((b - 2) ** 2 + 4)


def _ns_from_branch(b0):
    """The NS point located by one-parameter continuation in a at b = b0."""

    def at_b(y):
        ok, G, DG, A = family(np.r_[y, b0])
        return ok, G, DG[:, :4], A

    s = 0.8  # a stable fixed point: a = s + b0 - 1 + 1 / s, determinant 1 / s - s + b0 - 1
    a = s + b0 - 1 + 1 / s
    _, _, bifs, _ = pseudo_arclength(at_b, np.array([s, s, 0.0, a]), 1, (0.0, 10.0), **KW)
    ns = [x for k, _, _, x in bifs if k == "neimark-sacker"]
    assert len(ns) == 1, bifs
    return np.r_[ns[0], b0]


@pytest.mark.parametrize("direction", [1, -1])
def test_ns_curve_angle_and_strong_resonances(direction):
    x0 = _ns_from_branch(0.5)
    assert abs(x0[3] - a_ns(0.5)) < 1e-8  # the one-parameter locator's tolerance
    xs, mults, codim2, status = follow_ns_curve(family, x0, direction, (-3.0, 3.0), **KW)
    theta, a, b = xs[:-1, 3], xs[:-1, 4], xs[:-1, 5]  # the last point: the resonance
    assert len(xs) > 30
    np.testing.assert_allclose(a, a_ns(b), rtol=0, atol=1e-10)
    np.testing.assert_allclose(theta, np.arccos(b / 2), rtol=0, atol=1e-8)
    np.testing.assert_allclose(xs[:, 0], (xs[:, 4] - 1) / 2, rtol=0, atol=1e-10)
    # the multipliers: e^{+-i theta} (largest modulus first) and 0.3 + 0.1 s
    np.testing.assert_allclose(np.abs(mults[:-1, :2]), 1.0, atol=1e-10)
    np.testing.assert_allclose(mults[:-1, 2].real, 0.3 + 0.1 * xs[:-1, 0], atol=1e-12)
    found = {k: x[3:] for k, _, x in codim2}
    if direction == 1:  # towards b = 2: the curve ends in the 1:1 resonance
        assert status == "1:1" and list(found) == ["1:1"], codim2
        np.testing.assert_allclose(found["1:1"], [0.0, 3.0, 2.0], atol=1e-6)
    else:  # towards b = -2 through 1:4 and 1:3 into 1:2
        assert status == "1:2" and list(found) == ["1:4", "1:3", "1:2"], codim2
        np.testing.assert_allclose(found["1:4"], [math.pi / 2, 2 * math.sqrt(2) - 1, 0.0],
                                   atol=1e-9)  # fmt: skip
        np.testing.assert_allclose(found["1:3"], [2 * math.pi / 3, math.sqrt(13) - 2, -1.0], atol=1e-9)  # fmt: skip
        np.testing.assert_allclose(found["1:2"], [math.pi, 2 * math.sqrt(5) - 3, -2.0], atol=1e-6)
    np.testing.assert_array_equal(xs[-1, 3:], codim2[-1][2][3:])


def test_ns_curve_ends_on_the_bound_of_the_second_parameter():
    x0 = _ns_from_branch(0.5)
    xs, _, codim2, status = follow_ns_curve(family, x0, -1, (-0.5, 3.0), **KW)
    assert status == "bounds" and xs[-1, 5] == -0.5
    assert [k for k, _, _ in codim2] == ["1:4"]
    np.testing.assert_allclose(xs[-1, [3, 4]], [math.acos(-0.25), a_ns(-0.5)], atol=1e-10)


def test_no_complex_pair_is_reported():
    x0 = np.array([0.1, 0.1, 0.0, 0.7, 3.0])  # determinant 0.5, trace 3: real multipliers
    xs, _, _, status = follow_ns_curve(family, x0, 1, (2.5, 3.5), **KW)
    assert xs is None and status == "no-complex-pair"


def test_curve_file_round_trip_of_the_optional_fields(tmp_path):
    import stickslip_fast as ssf

    s = ssf.System.preset("asymmetric", eta=3.3)
    common = dict(
        system=s, param="eta", param2="k12", period=1, values=np.array([[3.3, -0.8]]),
        points=np.arange(4.0)[None, :], T=np.array([14.0]),
        multipliers=np.array([[np.exp(1j), np.exp(-1j), 0.1]]), status="bounds",
    )  # fmt: skip
    ns = ssf.Curve(kind="neimark-sacker", theta=np.array([1.0]), **common)
    back = ssf.Curve.from_hdf5(ns.to_hdf5(tmp_path / "ns.h5"))
    np.testing.assert_array_equal(back.theta, [1.0])
    assert back.event is None and back.event_time is None
    event = {"disk": 0, "extremum": "min", "threshold": 100.0}
    st = ssf.Curve(kind="stick-phase", event=event, event_time=np.array([2.5]), **common)
    back = ssf.Curve.from_hdf5(st.to_hdf5(tmp_path / "st.h5"))
    assert back.kind == "stick-phase" and back.event == event and back.theta is None
    np.testing.assert_array_equal(back.event_time, [2.5])


NS_ANGLE = 1.0


def turning_ns(x):
    # z -> A z, A = Q(phi) diag(r Rot(1), I2 / 2) Q(phi)^T with r = 1 + a - 0.3 sin(th):
    # the NS curve a = 0.3 sin(th) at angle 1; Q turns the plane of the complex pair
    # into the other two coordinates by phi(th), a quarter turn by th = 1.5, where the
    # complex null vector is orthogonal to the start's borders
    z, a, th = x[:4], x[4], x[5]
    Q, dQ = plane_turn(th)
    eye2, zero2 = np.eye(2), np.zeros((2, 2))
    rot = np.array([[math.cos(NS_ANGLE), -math.sin(NS_ANGLE)],
                    [math.sin(NS_ANGLE), math.cos(NS_ANGLE)]])  # fmt: skip
    r = 1.0 + a - 0.3 * np.sin(th)
    B = np.block([[r * rot, zero2], [zero2, 0.5 * eye2]])
    dB = np.block([[rot, zero2], [zero2, zero2]])  # dB / dr
    A = Q @ B @ Q.T
    dA_a = Q @ dB @ Q.T
    dA_th = dQ @ B @ Q.T + Q @ B @ dQ.T - 0.3 * np.cos(th) * dA_a
    return True, A @ z - z, np.column_stack([A - np.eye(4), dA_a @ z, dA_th @ z]), A


def test_ns_borders_follow_a_turning_complex_null_vector():
    # Fixed borders stop short of th = 1.5 (the bordered matrix is singular from there);
    # adapted borders end on the bound, on the curve a = 0.3 sin(th) at angle 1.
    x0 = np.array([0.0, 0.0, 0.0, 0.0, 1e-3, 0.0])
    kw = dict(KW, max_points=200)
    xs, _, _, status = follow_ns_curve(turning_ns, x0, 1, (-0.1, 3.2), borders="fixed", **kw)
    assert status != "bounds" and xs[-1, 6] < 1.5
    xs, _, codim2, status = follow_ns_curve(turning_ns, x0, 1, (-0.1, 3.2), **kw)
    assert status == "bounds" and xs[-1, 6] == 3.2
    np.testing.assert_allclose(xs[:, 5], 0.3 * np.sin(xs[:, 6]), rtol=0, atol=1e-11)
    np.testing.assert_allclose(xs[:, 4], NS_ANGLE, rtol=0, atol=1e-11)
    np.testing.assert_allclose(xs[:, :4], 0.0, atol=1e-11)
    assert codim2 == []


def test_ns_curve_names_where_the_stick_count_changes():
    # continue_bifurcation's stick watch on an NS curve (curve.StickWatch): the count is
    # read at (z, l1, l2), the angle theta left out of the point (curve._without_theta).
    # A count that steps from 1 to 2 where b falls through 0.2 is located there to 1e-8
    # in b, with the curve's a and theta there.
    import functools

    from stickslip_fast.bifurcation.curve import StickWatch, _without_theta

    seen = []

    def count_at(x):  # x = (u, v, w, a, b): the curve point without theta
        seen.append(x.size)
        return 1 if x[-1] > 0.2 else 2

    watch = StickWatch(functools.partial(_without_theta, count_at, 3), 1e-12)
    x0 = _ns_from_branch(0.5)
    xs, _, codim2, status = follow_ns_curve(family, x0, -1, (0.0, 3.0), watch=watch, **KW)
    assert status == "bounds" and set(seen) == {5}
    stick = [(i, x) for k, i, x in codim2 if k == "stick-phase"]
    assert len(stick) == 1, codim2
    i, x = stick[0]
    assert abs(x[5] - 0.2) < 1e-8 and xs[i, 5] > 0.2 > xs[i + 1, 5]
    np.testing.assert_allclose(x[[3, 4]], [math.acos(0.1), a_ns(0.2)], atol=1e-7)
