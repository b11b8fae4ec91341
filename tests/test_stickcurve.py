"""The stick-phase event curve (issue 28, item 2) of Fig. 12's period-2 orbit (DC motor, N
= 1) in (eta, k12), against the events located by one-parameter continuation (bisection on
the stick-phase count, :func:`~stickslip_fast.stick_phases`, independent of the extremum
machinery of the curve). Slow on a loaded machine: the curve and three one-parameter
continuations of a period-2 orbit with stick events.

At eta = 7.6665161 a local maximum of the slip speed inside the long stick phase (a
micro-slip) rises through the stick threshold 100 eps along the branch: the count goes
from 1 to 2 (docs/orbits.md, "Stick-phase event curves").
"""

from __future__ import annotations

import numpy as np
import pytest

import stickslip_fast as ssf

# a point of the P2 branch of data/continuation/fig12_p2.toml, before the event
ETA0 = 7.649827263760607
Z0 = np.array([-0.031603656037365875, 0.0, 0.14915739910072962, -0.006592611572902248,
               0.00983875819861892])  # fmt: skip


def _event(eta, k12, z, lo, hi, ds=0.01):
    s = ssf.System.preset("asymmetric", drive="dc-motor", eta=eta, k12=k12)
    orbit = ssf.find_orbit(s, z, 2)
    assert orbit.converged, orbit
    branch = ssf.continue_orbit(orbit, "eta", (lo, hi), ds=ds, ds_max=2 * ds, max_points=8)
    events = [b for b in branch.bifurcations if b.kind == "stick-phase"]
    assert len(events) == 1, branch.summary()
    return branch, events[0]


@pytest.fixture(scope="module")
def curve():
    branch, event = _event(ETA0, -0.8, Z0, ETA0, 7.70)
    assert abs(event.value - 7.666516105) < 1e-8  # docs/reproduction.md: 7.666516104
    return ssf.continue_bifurcation(branch, event, "k12", (-0.804, -0.79), direction=-1,
                                    ds=0.002, ds_max=0.002, max_points=4)  # fmt: skip


def _count(eta, k12, z, n_samples):
    s = ssf.System.preset("asymmetric", drive="dc-motor", eta=eta, k12=k12)
    orbit = ssf.find_orbit(s, z, 2)
    assert orbit.converged, orbit
    return ssf.stick_phases(s, orbit.points[0], orbit.T, n_samples=n_samples).size


def test_stick_event_curve_separates_one_and_two_stick_phases(curve):
    assert curve.kind == "stick-phase" and curve.period == 2 and curve.status == "max-points"
    assert curve.event["disk"] == 0 and curve.event["extremum"] == "max"
    assert curve.event["threshold"] == 100.0 and len(curve.values) == 4
    assert np.all(np.diff(curve.values[:, 1]) < 0) and np.all(np.diff(curve.values[:, 0]) > 0)
    assert np.all(np.abs(curve.event_time - 6.1) < 0.05)  # the micro-slip's maximum
    # the branch's event (the count of 20 000 samples per period, bisection to 1e-8) lies
    # past the curve's start by the sampling's bias: a sampled maximum is below the true
    # one by ~s'' dt^2 / 8 (dt = T / 20000 = 2.3e-3), so it reaches the threshold later
    assert 0 < 7.666516105 - curve.values[0, 0] < 5e-7
    # with 10x denser sampling (bias ~100x smaller) the count changes within 1e-7 of the
    # curve, at the start and at the far end
    for j in (0, 3):
        eta_c, k12 = (float(v) for v in curve.values[j])
        assert _count(eta_c - 1e-7, k12, curve.points[j], 200_000) == 1
        assert _count(eta_c + 1e-7, k12, curve.points[j], 200_000) == 2
