"""An oscillation dying out is not an orbit: the fixed window's period test and its rest check.

A slowly decaying oscillation about a stable equilibrium has x1 minima that change by
less than the period tolerance per period long before it comes to rest, so
``detect_period`` alone reads it as period 1. ``orbit_period`` refuses such a period
where the points still drift beyond the tolerance *towards the rest state*
(``decays_to_rest``); a transient converging onto an orbit heads for a point of that
orbit and keeps its period. References: the settled run (30 000 time units), the
equilibrium's eigenvalues (Newton), and the model's equations at the rest position.
"""

import numpy as np
import pytest

import stickslip_fast as ssf
from stickslip_fast.cli.config import load_config
from stickslip_fast.core.poincare import (
    decays_to_rest,
    detect_period,
    envelope_decays,
    orbit_period,
)
from stickslip_fast.model.equations import rest_position, rhs

# The one wrong label of benchmarks/param_labels.py (seed 11, case 452): a one-disk
# system with light damping whose oscillation decays by rho = 0.992 per period.
DECAYING = ssf.System(
    m=3.7722696349412925, k12=0.25580465062501234, c=0.002117236312429971, c12=0.0,
    mu=0.01252387033190633, eps=1e-05, eta=5.765592478841798, drive="constant",
    vb=0.1358753657652291, n_oscillators=1,
)  # fmt: skip
# its state at t = 2400 of a run from the default start (a sample of that run): 300 more
# time units see the minima repeat within the tolerance, 1.3e-3 from rest
NEAR_REST = np.array([1.36279595e-02, 5.14630197e-04, -3.40679168e-03, 4.56404071e-05])


def _state_at_rest(system, vb):
    x, ph = rest_position(vb, system.to_array())
    y = np.zeros(system.n_state)
    y[0 : 4 * system.n_oscillators : 4] = x
    y[2 : 4 * system.n_oscillators : 4] = ph
    if system.is_dc_motor:
        y[-1] = vb
    return y


@pytest.mark.parametrize(
    "system",
    [
        DECAYING,
        ssf.System.preset("asymmetric"),
        ssf.System.preset("literature").replace(eps=1e-3, vb=0.5),
        ssf.System.preset("asymmetric").replace(drive="dc-motor", n_oscillators=3),
    ],
)
def test_rest_position_zeroes_the_disks_equations(system):
    # at rest every disk's accelerations vanish; on a DC motor at its sliding belt speed
    # (a root of the motor equation, from find_equilibrium) the motor's too
    vb = ssf.find_equilibrium(system).state[-1] if system.is_dc_motor else system.vb
    y = _state_at_rest(system, vb)
    f = np.empty_like(y)
    rhs(y, system.to_array(), system.n_oscillators, system.is_dc_motor, f)
    assert np.max(np.abs(f)) <= 1e-15
    # far outside the stick band the friction is mu (T_s = -1): x = mu / (1 - k12^2)
    x, ph = rest_position(vb, system.to_array())
    if vb > 1e3 * system.eps:
        lead = system.mu / (1.0 - system.k12**2)
        assert x == pytest.approx(lead, rel=1e-6 + 20 * (system.eps / vb) ** 2)
        assert ph == pytest.approx(-system.k12 * x, rel=1e-15)


def test_rest_position_is_nan_where_the_springs_hold_none():
    p = ssf.System.preset("asymmetric").replace(k12=1.0).to_array()
    assert all(np.isnan(rest_position(0.1, p)))


def test_a_decaying_oscillation_is_not_called_an_orbit():
    eq = ssf.find_equilibrium(DECAYING)
    assert eq.stable and eq.eigenvalues[0].real > -2e-3  # a stable, weakly damped focus
    settled = ssf.simulate(DECAYING, 30_000.0, dwell=5000.0)
    assert settled.status == "equilibrium"
    res = ssf.simulate(DECAYING, 3000.0)  # the default window
    assert (res.status, res.period) == ("ok", 0)
    # the period test alone still reads its points as period 1: the refusal is the check's
    pts = res.poincare
    tol = res.settings.period_tol
    assert detect_period(pts, len(pts), tol, 64) == 1
    p = DECAYING.to_array()
    assert decays_to_rest(pts, len(pts), 1, tol, p, 1, False)
    # the sweep kernel's label is the same
    sw = ssf.sweep(DECAYING, "eta", [DECAYING.eta], t_end=3000.0, progress=False)
    assert (sw.status[0], sw.period[0]) == ("ok", 0)
    # and so is converged stopping's, which reaches its cap unconverged
    conv = ssf.simulate(DECAYING, 3000.0, stop="converged")
    assert (conv.status, conv.period) == ("ok", 0) and np.isnan(conv.t_converged)


def test_a_short_window_near_rest_is_not_called_an_orbit():
    res = ssf.simulate(DECAYING, 300.0, t_transient=0.0, y0=NEAR_REST, max_points=32)
    pts = res.poincare
    assert detect_period(pts, len(pts), res.settings.period_tol, 64) == 1
    assert (res.status, res.period) == ("ok", 0)


#: A case of benchmarks/param_labels.py (seed 404, case 405 of 500): a heavy disk whose
#: two modes (x1 at 1.005 rad per unit time, phi1 at 0.096) both still ring at t = 3000.
TWO_MODES = ssf.System(m=51.397640960257654, k12=-0.7226185384066025, c=0.0034091001182898098,
                       mu=0.043813048833287696, eta=3.5545746457061966, vb=0.09592617585554067,
                       vb0=0.09592617585554067)  # fmt: skip
TWO_MODES_START = np.array([0.09676200390104982, 0.030625554961573084, 0.11665199800853898,
                            -0.01539034116311215])  # fmt: skip


def test_a_decay_of_two_modes_at_once_is_not_called_an_orbit():
    # Met in 1 of 3000 random systems (label rules 3 read period 1): the slow phi1 mode
    # beats against x1, so the changes of the x1 minima are not geometric over two periods
    # and decays_to_rest does not see them head for rest. The run is at rest by t = 4000
    # and stays there; the envelope of the window's last points (envelope_decays, rules 4)
    # heads for rest
    eq = ssf.find_equilibrium(TWO_MODES)
    assert eq.stable and max(eq.eigenvalues.real) > -2e-3
    later = ssf.simulate(TWO_MODES, 4000.0, t_transient=3000.0, y0=TWO_MODES_START)
    assert later.status == "equilibrium"
    for t_end in (2500.0, 3000.0, 3200.0):  # the default window and either side of it
        res = ssf.simulate(TWO_MODES, t_end, y0=TWO_MODES_START)
        assert (res.status, res.period) == ("ok", 0), (t_end, res.status, res.period)
        # the reading of rules 3 on the same points: period 1 at t_end 3000 and 3200
        per = detect_period(res.poincare, len(res.poincare), res.settings.period_tol, 64)
        assert per == (0 if t_end == 2500.0 else 1)
    # stop="converged" reaches its cap unconverged and is judged there: the same reading
    conv = ssf.simulate(TWO_MODES, 3000.0, y0=TWO_MODES_START, stop="converged")
    assert np.isnan(conv.t_converged) and conv.period == 0


def test_the_envelope_rule_on_constructed_points():
    # two modes decaying at once about rest (x1 at 1.005, phi1 at 0.096 rad per unit time,
    # as TWO_MODES), sampled once per fast period: period 1 by the tolerance, decay by the
    # envelope; the same points with the decay taken out (a quasi-periodic ring of constant
    # envelope) or converging onto an orbit of half the size are not refused
    p = TWO_MODES.to_array()
    x0, ph0 = rest_position(TWO_MODES.vb, p)
    t = np.arange(480) * 2 * np.pi / 1.005
    fast, slow = np.exp(-0.0017 * t), np.exp(-0.0030 * t)
    beat = 1 + 0.3 * np.cos(0.096 * t)
    rest = np.array([x0, 0.0, ph0, 0.0])

    def points(envelope):
        pts = np.tile(rest, (len(t), 1))
        pts[:, 0] -= 0.15 * envelope * beat
        pts[:, 2] += 0.05 * envelope * np.cos(0.096 * t)
        return pts

    args = (1e-5, p, 1, False)
    decay = points(0.7 * fast + 0.3 * slow)
    assert envelope_decays(decay, len(t), 1, *args)
    assert not envelope_decays(points(np.ones_like(t)), len(t), 1, *args)
    assert not envelope_decays(points(0.5 + 0.5 * fast), len(t), 1, *args)
    # too few points for blocks of 4 periods: the rule says nothing
    assert not envelope_decays(decay[-31:], 31, 1, *args)
    # a ring buffer holds the last points: the same verdict from any rotation of it
    rolled = np.roll(decay, 17, axis=0)
    assert envelope_decays(rolled, len(t) + 17, 1, *args)


def test_an_orbit_still_converging_keeps_its_period():
    # Fig. 14 at eta = 6.2: at t_end its minima still drift 4.5 tolerances, with
    # rho = 0.909, onto the period-1 orbit 0.26 from rest; a window of 20 000 confirms it
    cfg = load_config("data/fig14_symmetric_dcmotor_N2.toml")
    system = cfg.system.replace(eta=6.2)
    kw = dict(t_transient=cfg.integration["t_transient"], max_points=256, y0=cfg.y0)
    res = ssf.simulate(system, cfg.integration["t_end"], **kw)
    assert (res.status, res.period) == ("ok", 1)
    pts, tol = res.poincare, res.settings.period_tol
    scale = 1.0 + np.abs(pts[-3:]).max()
    d1 = np.abs(pts[-1] - pts[-2]).max()
    d0 = np.abs(pts[-2] - pts[-3]).max()
    rho = d1 / d0
    assert d1 * rho / (1 - rho) > 3 * tol * scale  # the rest check is asked, and says no
    assert not decays_to_rest(pts, len(pts), 1, tol, system.to_array(), 2, True)
    long = ssf.simulate(system, 20_000.0, **kw)
    assert (long.status, long.period) == ("ok", 1)
    assert np.abs(long.poincare[-1] - pts[-1]).max() < 1e-3


@pytest.mark.parametrize(
    ("offset", "size", "rho", "n", "decays"),
    [
        (0.0, 1e-3, 0.99, 40, True),  # minima contracting onto the rest state
        (0.05, 1e-3, 0.99, 40, False),  # the same contraction onto a point 0.05 from rest
        (0.0, 1e-3, 1.0, 40, False),  # equal changes: no contraction to extrapolate
        (0.0, 6.4e-4, 0.5, 8, False),  # at its limit within the tolerance already
    ],
)
def test_decays_to_rest_on_constructed_sequences(offset, size, rho, n, decays):
    system = ssf.System.preset("asymmetric")
    p = system.to_array()
    limit = _state_at_rest(system, system.vb)
    limit[[0, 3]] += [-offset, 0.4 * offset]
    direction = np.array([-1.0, 0.0, 0.25, 0.5])  # dx1 = 0 at a minimum of x1
    if rho == 1.0:
        pts = np.array([limit + size * direction * (1 - 0.007 * k) for k in range(n)])
    else:
        pts = np.array([limit + size * direction * rho**k for k in range(n)])
    tol = 1e-5
    assert detect_period(pts, n, tol, 64) == 1  # every case repeats within the tolerance
    assert decays_to_rest(pts, n, 1, tol, p, 1, False) is decays
    assert orbit_period(pts, n, tol, 64, p, 1, False) == (0 if decays else 1)
