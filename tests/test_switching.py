"""Branch switching with multiple shooting (issue 28, item 1): the period-4 orbit born at
the subcritical period-doubling of Fig. 6's period-2 orbit (eta = 5.042952433), polished by
multiple shooting, equals the single-shooting one, and its branch goes on by multiple
shooting. About 30 s warm."""

from __future__ import annotations

import numpy as np
import pytest

import stickslip_fast as ssf

P2_ETA = 5.043198103554579
P2_POINT = np.array([0.027234629670059556, 0.0, 0.12785148813700828, -0.0038733936156032087])


@pytest.fixture(scope="module")
def p2_branch():
    o2 = ssf.find_orbit(ssf.System.preset("asymmetric", eta=P2_ETA), P2_POINT, period=2)
    br = ssf.continue_orbit(o2, "eta", (5.0428, 5.0433), ds=2e-5, ds_min=1e-9, ds_max=4e-5,
                            max_points=8, direction=-1)  # fmt: skip
    return br, [b for b in br.bifurcations if b.kind == "period-doubling"][0]


def test_switch_by_multiple_shooting_equals_single_and_continues(p2_branch):
    br, pd = p2_branch
    single = ssf.switch_branch(br, pd)
    multi = ssf.switch_branch(br, pd, shooting="multiple", segments=8)
    assert single.converged and multi.converged and multi.period == 4
    assert multi.system == single.system  # the same corrected start
    np.testing.assert_allclose(multi.points, single.points, atol=1e-9)
    assert abs(multi.T - single.T) < 1e-8
    # the multipliers from the segments' factors (periodic QR) against the one-piece
    # Jacobian's (they differ by 7.6e-6: the variational Jacobian's accuracy on this
    # stiff orbit, as on the period-doubling curve, docs/orbits.md)
    np.testing.assert_allclose(multi.multipliers[0], single.multipliers[0], rtol=3e-5)
    assert 1.0 < abs(multi.multipliers[0]) < 1.1 and not multi.stable
    away = float(np.sign(multi.system.eta - pd.value))
    doubled = ssf.continue_orbit(multi, "eta", (5.0428, 5.0433), direction=away, ds=1e-6,
                                 ds_max=4e-6, max_points=5, shooting="multiple", segments=8)  # fmt: skip
    assert len(doubled.values) == 5 and doubled.period == 4
    assert np.all(np.diff(doubled.values) * away > 0)


def test_switch_with_auto_takes_single_shooting_where_it_converges(p2_branch):
    # "auto" polishes by single shooting and hands over to multiple shooting only where
    # single shooting fails; at this period-doubling (mu 1.009) it converges, so "auto"
    # gives the single-shooting orbit, bit for bit
    br, pd = p2_branch
    single = ssf.switch_branch(br, pd)
    auto = ssf.switch_branch(br, pd, shooting="auto")
    assert auto.converged and auto.period == 4 and auto.system == single.system
    np.testing.assert_array_equal(auto.points, single.points)
    assert auto.T == single.T
    np.testing.assert_array_equal(auto.multipliers, single.multipliers)


def test_switch_rejects_bad_shooting(p2_branch):
    br, pd = p2_branch
    with pytest.raises(ValueError, match="shooting"):
        ssf.switch_branch(br, pd, shooting="double")
    with pytest.raises(ValueError, match="segments"):
        ssf.switch_branch(br, pd, shooting="multiple", segments=0)


def test_continue_orbit_defaults_walk_away_from_the_switched_orbit_s_origin():
    # continue_orbit's ds and direction, when not given, from Orbit.origin (switch_branch
    # sets it): away from the bifurcation in its parameter, from a branch point with the
    # small first step; explicit arguments win, and another parameter ignores the origin
    from stickslip_fast.bifurcation.walk_args import (
        BRANCH_POINT_DS,
        DEFAULT_DS,
        _walk_defaults,
    )  # fmt: skip

    s = ssf.System.preset("asymmetric", eta=2.0)
    nan = np.full((1, 4), np.nan)
    orbit = ssf.Orbit(s, 1, nan, np.ones(1), 1.0, np.ones(3), False, np.eye(3), 0.0, 0, True,
                      "converged")  # fmt: skip
    assert _walk_defaults(orbit, "eta", None, None) == (DEFAULT_DS, 1.0)
    for kind, value, expected in (("branch-point", 2.5, (BRANCH_POINT_DS, -1.0)),
                                  ("branch-point", 1.5, (BRANCH_POINT_DS, 1.0)),
                                  ("period-doubling", 2.1, (DEFAULT_DS, -1.0)),
                                  ("symmetry-breaking", 1.9, (DEFAULT_DS, 1.0))):  # fmt: skip
        orbit.origin, orbit.origin_param = ssf.Bifurcation(kind, value, 0, nan[0]), "eta"
        assert _walk_defaults(orbit, "eta", None, None) == expected
        assert _walk_defaults(orbit, "eta", 0.02, 1.0) == (0.02, 1.0)
        assert _walk_defaults(orbit, "mu", None, None) == (DEFAULT_DS, 1.0)
