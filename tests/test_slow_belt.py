"""Rest and dwell at slow belt speeds: a sticking disk rides with the belt.

The fixed defaults equilibrium_tol = 1e-4 and dwell = 200 were set at the presets' belt
speed v_b = 0.0112. At v_b = 1e-4 a stick phase moves the disk at 1e-4 for some 700
time units, and with them the stick-slip orbits of Fig. 6 read as "equilibrium"
(benchmarks/belt_speed.py). The defaults now follow the belt speed.
"""

from __future__ import annotations

import warnings

import numpy as np
import pytest

import stickslip_fast as ssf
from stickslip_fast.core.settings import (
    DEFAULT_DWELL,
    DEFAULT_EQUILIBRIUM_TOL,
    default_dwell,
    default_equilibrium_tol,
)
from stickslip_fast.model.system import slowest_belt_speed

SLOW = ssf.System.preset("asymmetric", eta=6.0, vb=1e-4)


def test_the_defaults_follow_the_belt_speed_and_keep_the_presets():
    assert default_equilibrium_tol(0.0112) == DEFAULT_EQUILIBRIUM_TOL == 1e-4
    assert default_equilibrium_tol(0.15) == 1e-4  # the literature set
    assert default_equilibrium_tol(1e-4) == pytest.approx(1e-6, rel=1e-15)
    assert default_equilibrium_tol(-1e-3) == pytest.approx(1e-5, rel=1e-15)
    assert default_equilibrium_tol(None) == 1e-4
    assert default_dwell(0.0112) == DEFAULT_DWELL == 200.0
    assert default_dwell(0.15) == 200.0
    assert default_dwell(1e-4) == pytest.approx(200.0 * 112, rel=1e-12)
    assert default_dwell(None) == 200.0


def test_the_slowest_belt_speed_is_the_drives_own():
    asym = ssf.System.preset("asymmetric")
    assert slowest_belt_speed(asym.replace(vb=-3e-3, vb0=1.0)) == 3e-3
    dc = asym.replace(drive="dc-motor", vb=1.0, vb0=2e-3)
    assert slowest_belt_speed(dc) == 2e-3
    # a swept belt speed: its smallest nonzero magnitude; a belt at rest sets no scale
    assert slowest_belt_speed(asym, ("vb", "eta"), ([0.0, -5e-4, 0.01], [2.0])) == 5e-4
    assert slowest_belt_speed(asym, ("vb0",), ([1e-6],)) == 0.0112  # vb0 drives no belt here
    assert slowest_belt_speed(asym.replace(vb=0.0)) is None


def test_stick_slip_at_a_slow_belt_is_not_called_rest():
    # the window as long in belt travel as the presets' 3000 time units
    long = dict(t_end=3000.0 * 112, t_transient=2000.0 * 112)
    r = ssf.simulate(SLOW, **long)
    assert (r.status, r.period) == ("ok", 2)
    assert r.settings["equilibrium_tol"] == pytest.approx(1e-6)
    assert r.settings["dwell"] == pytest.approx(22400.0)
    # the settled run (ten times tighter rest) agrees; the old fixed defaults said rest
    settled = ssf.simulate(SLOW, 9000.0 * 112, 6000.0 * 112, equilibrium_tol=1e-7)
    assert (settled.status, settled.period) == ("ok", 2)
    np.testing.assert_allclose(r.poincare[-2:], settled.poincare[-2:], rtol=0, atol=1e-6)
    old = ssf.simulate(SLOW, **long, equilibrium_tol=1e-4, dwell=200.0)
    assert old.status == "equilibrium"
    # converged stopping finds the orbit too, and the presets' short window no rest
    conv = ssf.simulate(SLOW, 3000.0 * 112, stop="converged")
    assert (conv.status, conv.period) == ("ok", 2)
    short = ssf.simulate(SLOW, 3000.0, 2000.0)
    assert short.status not in ("equilibrium", "stalled")


def test_a_sweep_and_a_census_over_the_belt_speed_take_its_slowest_value():
    asym = ssf.System.preset("asymmetric", eta=6.0)
    kw = dict(t_end=50.0, progress=False)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UserWarning)  # no orbit in 50 time units
        swept = ssf.sweep(asym, "vb", [0.0112, 1e-4], **kw)
        plane = ssf.census(asym, ("eta", "vb"), ([6.0], [1e-3, 0.0112]), n_starts=2, **kw)
        given = ssf.sweep(asym, "vb", [1e-4], equilibrium_tol=1e-5, dwell=300.0, **kw)
        preset = ssf.sweep(asym, "eta", [6.0], **kw)
    assert swept.settings["equilibrium_tol"] == pytest.approx(1e-6)
    assert swept.settings["dwell"] == pytest.approx(22400.0)
    assert plane.settings["equilibrium_tol"] == pytest.approx(1e-5)
    assert (given.settings["equilibrium_tol"], given.settings["dwell"]) == (1e-5, 300.0)
    # at the presets' belt speed the record is the one written before (dwell at its
    # default is left out of the configuration, so old files keep their hash)
    assert preset.settings["equilibrium_tol"] == 1e-4
    assert "dwell" not in preset.settings.to_dict()


def test_a_swept_belt_speed_replaces_the_systems_own():
    slow = ssf.System.preset("asymmetric", vb=1e-4)
    assert slowest_belt_speed(slow, ("vb",), ([0.05, 0.1],)) == 0.05
    assert slowest_belt_speed(slow, ("eta",), ([2.0],)) == 1e-4
    assert slowest_belt_speed(slow, ("vb",), ([0.0],)) is None
