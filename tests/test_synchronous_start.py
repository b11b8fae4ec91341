"""Identical disks started alike on one DC motor stay alike: the default start warns.

The model treats every disk with the same arithmetic, so from the zero state (the
default ``y0``) N >= 2 disks on a shared motor stay bit-identical for ever and a run
only sees the synchronous (in-phase) subspace. On the symmetric set at eta = 5 the
in-phase orbit found there is unstable across the disks (leading multiplier 1.0923,
the growth per period of an antisymmetric difference), while the paper's start for
Fig. 14 (disk 2 displaced) settles in anti-phase.
"""

from __future__ import annotations

import warnings

import numpy as np
import pytest

import stickslip_fast as ssf

SYM_DC2 = ssf.System.preset("symmetric", drive="dc-motor", eta=5.0, n_oscillators=2)
SHORT = dict(t_end=50.0, max_points=16)
# Fig. 14's start in the engine's per-disk order (x, dx, phi, dphi per disk, then v_b)
PAPER_Y0 = [0.0, 0.0, 0.0, 0.0, 0.05, 0.05, 0.0, 0.0, 0.0]


def _caught(call):
    with warnings.catch_warnings(record=True) as seen:
        warnings.simplefilter("always")
        call()
    return [w for w in seen if issubclass(w.category, ssf.SynchronousStartWarning)]


def test_the_default_start_of_disks_on_one_motor_warns_at_the_callers_line():
    for call in (
        lambda: ssf.simulate(SYM_DC2, **SHORT),
        lambda: ssf.sweep(SYM_DC2, "eta", [5.0], progress=False, **SHORT),
        lambda: ssf.census(SYM_DC2, "eta", [5.0], n_starts=2, progress=False, **SHORT),
    ):
        seen = _caught(call)
        assert len(seen) == 1
        assert seen[0].filename == __file__  # points at the user's call, not at the package
        assert "2 disks in the same state" in str(seen[0].message)


@pytest.mark.parametrize(
    "call",
    [
        lambda: ssf.simulate(SYM_DC2, y0=PAPER_Y0, **SHORT),
        lambda: ssf.sweep(SYM_DC2, "eta", [5.0], y0=PAPER_Y0, progress=False, **SHORT),
        lambda: ssf.census(
            SYM_DC2, "eta", [5.0], n_starts=2, include_zero=False, **SHORT, progress=False
        ),  # fmt: skip
        # one disk, or uncoupled disks on a constant belt: nothing to warn about
        lambda: ssf.simulate(ssf.System.preset("symmetric", drive="dc-motor"), **SHORT),
        lambda: ssf.simulate(ssf.System.preset("symmetric", n_oscillators=2), **SHORT),
    ],
)
def test_distinct_starts_one_disk_or_a_constant_belt_do_not_warn(call):
    assert _caught(call) == []


def test_synchronous_start_is_every_disk_in_disk_ones_state():
    assert SYM_DC2.synchronous_start(np.zeros(9))
    assert SYM_DC2.synchronous_start([0.1, 0.2, 0.3, 0.4, 0.1, 0.2, 0.3, 0.4, 0.01])
    assert not SYM_DC2.synchronous_start(PAPER_Y0)
    assert not SYM_DC2.synchronous_start([0.1, 0.2, 0.3, 0.4, 0.1, 0.2, 0.3, 0.4 + 1e-15, 0.0])


def test_what_the_warning_is_about_an_unstable_in_phase_orbit():
    # from rest the disks stay bit-identical and settle on a period-1 orbit of the
    # synchronous subspace, whose leading multiplier across the disks is > 1
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ssf.SynchronousStartWarning)
        r = ssf.simulate(SYM_DC2, 20000, stop="converged")
    assert (r.status, r.period) == ("ok", 1)
    assert np.array_equal(r.poincare[:, :4], r.poincare[:, 4:8])
    o = ssf.find_orbit(SYM_DC2, r)
    assert o.converged and not o.stable
    assert abs(o.multipliers[0] - 1.0923) < 1e-3
    # a difference of 1e-9 between the disks grows by that multiplier per period (the run
    # ends mid-period: at a Poincare point the disks creep, which reads as not settled)
    y = o.points[0].copy()
    y[4] += 1e-9
    b = ssf.simulate(SYM_DC2, 12.5 * o.T, y0=y, rtol=1e-12, atol=1e-14, max_points=100)
    d = np.abs(b.poincare[:, 0] - b.poincare[:, 4])
    growth = np.median(d[4:12] / d[3:11])  # the stable directions (|mu| <= 0.48) decayed
    assert abs(growth - o.multipliers[0].real) < 1e-4  # measured: 1.09231 against 1.092319
    # the paper's start (disk 2 displaced) settles in anti-phase instead: the disks' minima
    # of x are half a period apart, so at disk 1's minimum disk 2 is far from its own
    p = ssf.simulate(SYM_DC2, 20000, stop="converged", y0=PAPER_Y0)
    assert (p.status, p.period) == ("ok", 1)
    assert abs(p.poincare[-1, 4] - p.poincare[-1, 0]) > 0.1
