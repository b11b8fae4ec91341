"""In-phase orbits of N identical disks: transverse and longitudinal multipliers.

References that do not go through the split: the multipliers of the whole return map
(find_orbit), one disk's orbit on the same motor (the in-phase motion of N disks), a
brute-force run in which a small difference between the disks shrinks by the
transverse multiplier each period, and tight-tolerance find_orbit runs on both sides of
the symmetry-breaking point located by continuation.
"""

from __future__ import annotations

import dataclasses
import warnings

import numpy as np
import pytest

import stickslip_fast as ssf
from stickslip_fast.bifurcation.synchrony import synchronous_point


def _sym(n: int, eta: float, drive: str = "dc-motor") -> ssf.System:
    return ssf.System.preset("symmetric", drive=drive, n_oscillators=n, eta=eta)


def _in_phase_orbit(system: ssf.System) -> ssf.Orbit:
    # from rest the disks stay bit-identical (the warning says so; that is the point here)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ssf.SynchronousStartWarning)
        run = ssf.simulate(system, 3000, 2000)
    orbit = ssf.find_orbit(system, run)
    assert orbit.converged and orbit.period == 1
    return orbit


@pytest.fixture(scope="module")
def eta5():
    orbits = {n: _in_phase_orbit(_sym(n, 5.0)) for n in (1, 2, 3)}
    return orbits, {n: ssf.sync_stability(orbits[n]) for n in (2, 3)}


def _leading(mults: np.ndarray) -> np.ndarray:
    """The multipliers above the Jacobian's rounding (docs/orbits.md), sorted."""
    big = mults[np.abs(mults) > 1e-3]
    return np.sort_complex(big)


def test_the_split_gives_the_whole_maps_multipliers(eta5):
    orbits, split = eta5
    for n in (2, 3):
        s = split[n]
        assert s.multiplicity == n - 1
        together = np.concatenate([np.repeat(s.transverse, n - 1), s.longitudinal])
        assert together.size == orbits[n].multipliers.size
        np.testing.assert_allclose(
            _leading(together), _leading(orbits[n].multipliers), rtol=0, atol=1e-7
        )
        assert s.residual < 1e-8  # measured 2e-10 and 3e-10


def test_unstable_across_the_disks_at_eta_5_and_the_same_for_every_n(eta5):
    orbits, split = eta5
    s2, s3 = split[2], split[3]
    assert abs(s2.transverse[0] - 1.0923) < 1e-3  # tests/test_synchronous_start.py
    assert not s2.transverse_stable and s2.longitudinal_stable and not s2.stable
    assert s2.stable == orbits[2].stable
    # the motor feels the mean torque: N in-phase disks move as one disk does
    assert abs(orbits[2].T - orbits[1].T) < 1e-8 and abs(orbits[3].T - orbits[1].T) < 1e-8
    np.testing.assert_allclose(
        _leading(s2.longitudinal), _leading(orbits[1].multipliers), atol=1e-7
    )
    # N = 3 against N = 2: two integrations of different tangents (measured 4.5e-7)
    np.testing.assert_allclose(s3.transverse[:2], s2.transverse[:2], atol=2e-6)


def test_a_difference_between_the_disks_shrinks_by_the_transverse_multiplier():
    system = _sym(2, 3.0)
    s = ssf.sync_stability(_in_phase_orbit(system))
    assert s.transverse_stable and abs(s.transverse[0] - 0.6166) < 1e-3
    # start a difference along the leading transverse mode: at every local minimum of
    # x1 the difference between the disks is mu^k times the first (the section's timing
    # moves both disks alike, so it cancels in the difference)
    mu, vec = np.linalg.eig(s.transverse_block)
    k = int(np.argmax(np.abs(mu)))
    a = vec[:, k].real / np.max(np.abs(vec[:, k].real))
    y = s.orbit.points[0].copy()
    y[4:8] -= 1e-7 * a
    run = ssf.simulate(system, 8.5 * s.orbit.T, y0=y, rtol=1e-12, atol=1e-15, max_points=100)
    d = run.poincare[:, :4] - run.poincare[:, 4:8]
    ratios = np.linalg.norm(d[1:], axis=1) / np.linalg.norm(d[:-1], axis=1)
    assert ratios.size >= 6
    np.testing.assert_allclose(ratios, s.transverse[0].real, rtol=1e-4)  # measured 9e-6


@pytest.fixture(scope="module")
def in_phase_branch():
    orbit = _in_phase_orbit(_sym(2, 3.0))
    return orbit, ssf.continue_orbit(orbit, "eta", (3.0, 5.0))


def test_continuation_marks_the_symmetry_breaking_point(in_phase_branch, tmp_path):
    orbit, branch = in_phase_branch
    sb = [b for b in branch.bifurcations if b.kind == "symmetry-breaking"]
    assert len(sb) == 1 and sb[0].label == "SB"
    # the reference: a secant on the transverse multiplier of orbits found at
    # eta = 4.7638 and 4.7640 with rtol 1e-12, atol 1e-14, tangent_atol 1e-12 gave
    # 4.7638949 (the defaults give 4.7638974: the tangents' accuracy); measured 4.7638980
    assert abs(sb[0].value - 4.7638949) < 1e-5
    i = sb[0].index
    assert branch.stable[i] and not branch.stable[i + 1]
    for p in branch.points:
        assert synchronous_point(orbit.system, p)
    out = ssf.Branch.from_hdf5(branch.to_hdf5(tmp_path / "b.h5"))
    assert [b.kind for b in out.bifurcations] == [b.kind for b in branch.bifurcations]
    # both sides of it, at find_orbit's defaults
    for d, inside in ((-2e-4, True), (2e-4, False)):
        o = ssf.find_orbit(orbit.system.replace(eta=sb[0].value + d), sb[0].point)
        assert ssf.sync_stability(o).transverse_stable is inside


def test_no_symmetry_breaking_test_off_the_in_phase_subspace():
    one = _sym(1, 3.0)
    branch = ssf.continue_orbit(_in_phase_orbit(one), "eta", (3.0, 3.5))
    assert branch.values[-1] == pytest.approx(3.5)
    assert not [b for b in branch.bifurcations if b.kind == "symmetry-breaking"]


def test_uncoupled_disks_are_neutral_across_each_other():
    system = _sym(2, 5.0, drive="constant")
    orbit = _in_phase_orbit(system)
    s = ssf.sync_stability(orbit)
    # each disk keeps its own phase: a transverse multiplier is exactly 1
    assert abs(s.transverse[0] - 1.0) < 1e-5  # measured 2e-6
    assert not s.transverse_stable and s.longitudinal_stable
    assert not orbit.stable  # N - 1 multipliers are 1: never asymptotically stable
    one = _in_phase_orbit(_sym(1, 5.0, drive="constant"))
    assert one.stable


def test_errors_name_what_is_wrong():
    with pytest.raises(TypeError, match="orbit must be an Orbit"):
        ssf.sync_stability("orbit")
    one = _in_phase_orbit(_sym(1, 5.0))
    with pytest.raises(ValueError, match="N >= 2"):
        ssf.sync_stability(one)
    system = _sym(2, 5.0)
    paper_start = [0.0, 0.0, 0.0, 0.0, 0.05, 0.05, 0.0, 0.0, 0.0]  # Fig. 14: anti-phase
    anti = ssf.find_orbit(system, ssf.simulate(system, 20000, stop="converged", y0=paper_start))
    assert anti.converged
    with pytest.raises(ValueError, match="not in phase"):
        ssf.sync_stability(anti)
    with pytest.raises(ValueError, match="tol must be > 0"):
        ssf.sync_stability(_in_phase_orbit(system), tol=0.0)
    failed = ssf.find_orbit(system, np.zeros(9), max_iter=0)
    assert failed.status == "max-iter"
    with pytest.raises(ValueError, match="not converged"):
        ssf.sync_stability(failed)


def test_the_pitchfork_has_its_normal_form():
    # past the symmetry-breaking point a pair of stable orbits with the disks slightly
    # apart branches off (supercritical). Near it the normal form x' = a x - b x^3 gives:
    # the disks' difference squared grows linearly from eta*, and the critical multiplier
    # of the new orbit leaves 1 twice as fast as the in-phase orbit's transverse one.
    eta_sb = 4.7638980  # test_continuation_marks_the_symmetry_breaking_point
    system = _sym(2, 4.8)
    in_phase = _in_phase_orbit(system)
    y = in_phase.points[0].copy()
    y[4:6] += 1e-3
    apart = ssf.find_orbit(system, ssf.simulate(system, 20000, 10000, y0=y))
    etas = np.array([4.78, 4.79, 4.80])
    gaps, ratios = [], []
    for eta in etas:
        s = system.replace(eta=eta)
        o = ssf.find_orbit(s, apart.points[0])
        assert o.converged and o.stable and not synchronous_point(s, o.points[0])
        gaps.append(o.points[0][5])  # dx2 at disk 1's minimum of x (dx1 = 0 there)
        mu_t = ssf.sync_stability(ssf.find_orbit(s, in_phase.points[0])).transverse[0].real
        ratios.append((1.0 - o.multipliers[0].real) / (mu_t - 1.0))
    slope, icpt = np.polyfit(etas, np.square(gaps), 1)
    assert abs(-icpt / slope - eta_sb) < 1e-4  # measured 4e-5 (the cubic term's share)
    np.testing.assert_allclose(ratios, 2.0, rtol=0.03)  # measured 1.980-1.991


def test_switch_branch_at_the_symmetry_breaking_point(in_phase_branch):
    orbit, branch = in_phase_branch
    (sb,) = [b for b in branch.bifurcations if b.kind == "symmetry-breaking"]
    apart = ssf.switch_branch(branch, sb)
    assert apart.converged and apart.period == 1 and apart.stable
    eta = apart.system.eta
    assert not synchronous_point(apart.system, apart.points[0])
    # supercritical: the orbits apart exist where the in-phase one is unstable, close to
    # the point (the smallest offset that resolves them, 1e-6: measured 0.0037 above)
    assert 0.0 < eta - sb.value < 0.01
    # the normal form's factor 2 between the critical multipliers (measured 2.005)
    mu_t = ssf.sync_stability(ssf.find_orbit(apart.system, orbit.points[0])).transverse[0].real
    assert (1.0 - apart.multipliers[0].real) / (mu_t - 1.0) == pytest.approx(2.0, rel=0.03)
    # and from there on it is an ordinary branch (not in phase: no SB test)
    on = ssf.continue_orbit(apart, "eta", (eta, 5.0))
    assert on.values[-1] == pytest.approx(5.0) and on.stable.all()
    assert not on.bifurcations
    with pytest.raises(ValueError, match="in-phase"):
        fake = ssf.Bifurcation("symmetry-breaking", eta, 0, apart.points[0])
        ssf.switch_branch(dataclasses.replace(on, bifurcations=[fake]), fake)


def test_cli_continue_switches_at_the_symmetry_breaking_point(tmp_path, capsys):
    from stickslip_fast.cli import main

    cfg = tmp_path / "c.toml"
    cfg.write_text(
        '[system]\npreset = "symmetric"\ndrive = "dc-motor"\nn_oscillators = 2\neta = 4.7\n'
        "[initial]\ny0 = [0, 0, 0, 0, 0, 0, 0, 0, 0]\n"  # in phase, on purpose
        "[integration]\nt_end = 3000.0\nt_transient = 2000.0\n"
        '[continue]\nparam = "eta"\nbounds = [4.7, 4.8]\nswitch = true\n'
        'param2 = "beta"\nbounds2 = [0.0014, 0.0015]\nkinds2 = ["symmetry-breaking"]\n'
    )
    out = tmp_path / "b.h5"
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ssf.SynchronousStartWarning)
        assert main(["continue", str(cfg), "-o", str(out)]) == 0
    main_branch = ssf.Branch.from_hdf5(out)
    (sb,) = [b for b in main_branch.bifurcations if b.kind == "symmetry-breaking"]
    apart = ssf.Branch.from_hdf5(tmp_path / "b.sb1.h5")
    assert apart.period == 1 and 0 < apart.values[0] - sb.value < 0.01
    assert apart.values[-1] == pytest.approx(4.8) and apart.stable.all()
    assert not any(synchronous_point(apart.system, p) for p in apart.points)
    curve = ssf.Curve.from_hdf5(tmp_path / "b.curve1.h5")
    assert curve.kind == "symmetry-breaking" and curve.status == "bounds"
    assert curve.values[-1, 1] == pytest.approx(0.0015)
    assert curve.values[-1, 0] == pytest.approx(sb.value - 0.15, abs=0.02)  # dbeta/deta -6.6e-4
    captured = capsys.readouterr()
    assert "b.sb1.h5" in captured.out and "SB  symmetry-breaking" in captured.out
    # the start is in phase: its stability across the disks is reported (0.9774 measured)
    assert "leading multiplier across the disks 0.97" in captured.err + captured.out


def test_a_branch_of_in_phase_orbits_stays_in_phase():
    # next to the pitchfork the orbits with the disks apart lie ~1e-6 away; the walk is
    # projected onto the in-phase states (without: 6e-9 apart here, and from a start
    # 1e-7 off the subspace at beta = 0.0014106 a step of 0.01 landed on the orbits apart)
    system = _sym(2, 4.7419).replace(beta=0.00141)
    branch = ssf.continue_orbit(_in_phase_orbit(system), "eta", (4.7419, 4.7619))
    assert [b.kind for b in branch.bifurcations] == ["symmetry-breaking"]
    for p in branch.points:
        assert np.max(np.abs(p[:4] - p[4:8])) < 1e-12  # measured 3e-17


def test_the_curve_of_symmetry_breaking_points_in_the_motor_load(in_phase_branch, tmp_path):
    orbit, branch = in_phase_branch
    (sb,) = [b for b in branch.bifurcations if b.kind == "symmetry-breaking"]
    curve = ssf.continue_bifurcation(branch, sb, "beta", (0.0014, 0.01), max_points=12)
    assert curve.kind == "symmetry-breaking" and len(curve.values) == 12
    assert curve.values[-1, 1] > 0.00165  # measured (4.3337, 0.0016852)
    for i in (6, 11):
        eta, beta = curve.values[i]
        system = orbit.system.replace(eta=eta, beta=beta)
        # at the curve's parameters a transverse multiplier is 1 (find_orbit and the split)
        on = ssf.sync_stability(ssf.find_orbit(system, curve.points[i]))
        assert np.min(np.abs(on.transverse - 1.0)) < 5e-6  # measured 3e-7, 5e-7
        # and the one-parameter continuation at that beta locates its SB point there
        below = ssf.find_orbit(system.replace(eta=eta - 0.01), curve.points[i])
        one = ssf.continue_orbit(below, "eta", (eta - 0.01, eta + 0.01))
        (sb1,) = [b for b in one.bifurcations if b.kind == "symmetry-breaking"]
        assert abs(sb1.value - eta) < 1e-5  # measured 4.5e-7, 1.1e-6
    back = ssf.Curve.from_hdf5(curve.to_hdf5(tmp_path / "sb.h5"))
    assert back.kind == "symmetry-breaking"
    np.testing.assert_array_equal(back.values, curve.values)


def test_in_phase_and_anti_phase_motion_coexist_at_eta_3():
    # the paper sees anti-phase motion at eta = 3 (Fig. 14's start); the in-phase orbit is
    # stable there too (transverse multiplier 0.617), with a thin basin
    system = _sym(2, 3.0)
    g = np.linspace(-0.1, 0.1, 9)  # disk 2's (x, dx); disk 1 and the motor at rest
    r = ssf.basins(system, (g, g), plane=("x2", "dx2"), t_end=20000, progress=False)
    in_phase = [a for a in r.attractors if synchronous_point(system, a.points[0])]
    apart = [a for a in r.attractors if not synchronous_point(system, a.points[0])]
    assert len(in_phase) == 1 and len(apart) == 1
    assert apart[0].kind == "orbit" and abs(apart[0].points[0][4] - apart[0].points[0][0]) > 0.1
    assert r.labels[4, 5] == in_phase[0].id  # disk 2 started 0.025 faster: back in phase
    assert r.labels[6, 6] == apart[0].id  # the paper's start (0.05, 0.05)
    assert 0.02 < in_phase[0].fraction < 0.15  # measured 0.049 (0.070 on 25 x 25 cells)


def test_even_cuts_keep_single_shooting_s_pace_on_two_disks():
    # benchmarks/ms_mesh.py: the default mesh is refined where a segment amplifies by more
    # than 10, which cuts the orbit where the slip starts to grow out of the stick phase
    # (0.5-100 eps), and there Newton's reach is short: eta 3 -> 5 takes 87 points against
    # single shooting's 44. The 8 even cuts (max_segments=8) have no cut there (6 of 8 lie
    # deeper in the stick phase) and keep single shooting's pace.
    from stickslip_fast.bifurcation.stickphases import slip_velocity

    orbit = _in_phase_orbit(_sym(2, 3.0))
    system = orbit.system

    def cut_slips(mesh_starts):
        starts = np.asarray(mesh_starts[1])
        return (
            np.min([np.hypot(*slip_velocity(system, starts, i)) for i in range(2)], axis=0)
            / system.eps
        )

    refined = ssf.find_orbit(system, orbit.points[0], 1, shooting="multiple")
    in_breakaway = (cut_slips(refined.segments) > 0.5) & (cut_slips(refined.segments) < 100)
    assert refined.converged and in_breakaway.sum() >= 5  # measured 14 of 24 cuts
    kw = dict(progress=False, stick_events=False)
    single = ssf.continue_orbit(orbit, "eta", (3.0, 4.0), **kw)
    even = ssf.continue_orbit(orbit, "eta", (3.0, 4.0), shooting="multiple", max_segments=8, **kw)
    slips = cut_slips(even.segments[0])
    assert len(slips) == 8 and not np.any((slips > 0.5) & (slips < 100))
    assert single.status == even.status == "bounds", (single.status, even.status)
    # measured 25 points against 24
    assert even.values.size <= 1.25 * single.values.size, (even.values.size, single.values.size)
    assert abs(even.T[-1] - single.T[-1]) < 1e-8
    np.testing.assert_allclose(even.points[-1], single.points[-1], rtol=0, atol=1e-9)


def test_multiple_shooting_marks_the_symmetry_breaking_point():
    # the same point as test_continuation_marks_the_symmetry_breaking_point, by multiple
    # shooting (8 segments): the walk is projected onto the in-phase starts and the test
    # is det(Phi_d - I) from the segments' transverse factors
    orbit = _in_phase_orbit(_sym(2, 4.762))
    branch = ssf.continue_orbit(orbit, "eta", (4.762, 4.766), shooting="multiple")
    assert branch.values[-1] == pytest.approx(4.766)
    (sb,) = [b for b in branch.bifurcations if b.kind == "symmetry-breaking"]
    assert [b.kind for b in branch.bifurcations] == ["symmetry-breaking"]
    # the reference 4.7638949 (rtol 1e-12 secant, above); measured 4.76389485 (single
    # shooting at its defaults: 4.7638980, the tangents' accuracy)
    assert abs(sb.value - 4.7638949) < 2e-6
    assert branch.stable[sb.index] and not branch.stable[sb.index + 1]
    for p in branch.points:
        assert np.max(np.abs(p[:4] - p[4:8])) < 1e-12  # measured 5e-18
    for d, inside in ((-2e-4, True), (2e-4, False)):
        o = ssf.find_orbit(orbit.system.replace(eta=sb.value + d), sb.point)
        assert ssf.sync_stability(o).transverse_stable is inside
    # from its point a curve of SB points goes on as from single shooting's
    curve = ssf.continue_bifurcation(branch, sb, "beta", (0.0014, 0.01), max_points=3)
    assert curve.kind == "symmetry-breaking" and len(curve.values) == 3


@pytest.mark.parametrize("segments", [1, 3, 8])
def test_transverse_factors_give_the_transverse_multipliers(eta5, segments):
    # the segments' 4 x 4 factors multiply to Phi_d: their periodic-QR eigenvalues are
    # sync_stability's transverse multipliers (from the whole return map's Jacobian)
    from stickslip_fast.bifurcation.multishoot import MultiShooting, periodic_multipliers
    from stickslip_fast.bifurcation.multishoot_sync import (
        symmetry_breaking_test,
        transverse_factors,
    )

    orbits, stab = eta5
    orbit, ref = orbits[2], stab[2]
    ms = MultiShooting(orbit.system, segments, 1e-10, 1e-12, 1e-10)
    st, Y = ms.states_at(orbit.points[:1], orbit.T, ms.mesh[:-1] * orbit.T)
    status, G, _, factors = ms.evaluate(ms.pack(Y, orbit.T))
    assert st == status == "ok" and np.max(np.abs(G)) < 1e-9
    mu = periodic_multipliers(transverse_factors(orbit.system, orbit.points[0], factors))
    np.testing.assert_allclose(mu[:2].real, ref.transverse[:2].real, atol=1e-6)  # 3e-7
    assert np.all(np.abs(mu[2:]) < 1e-12) and np.all(np.abs(ref.transverse[2:]) < 1e-12)
    det = np.linalg.det(ref.transverse_block - np.eye(4))  # -0.13624
    test = symmetry_breaking_test(orbit.system, orbit.points[0], factors)
    assert test == pytest.approx(det, rel=1e-5)


def test_no_symmetry_breaking_test_for_multiple_shooting_off_the_in_phase_subspace():
    # the two disks apart (the anti-phase orbit of tests/test_branch_points.py) are not in
    # phase: multiple shooting neither projects them nor tests them for SB points
    from stickslip_fast.bifurcation.multishoot import MultiShooting
    from stickslip_fast.bifurcation.multishoot_sync import in_phase_start

    apart = ssf.find_orbit(_sym(2, 1.1275682582876292), np.array([
        0.03734505165096868, 0.0, 0.0, 0.0, 0.060820214617317424, 0.0009027951066187418,
        0.0, 0.0, 0.00979440927478325]))  # fmt: skip
    assert apart.converged and not synchronous_point(apart.system, apart.points[0])
    ms = MultiShooting(apart.system, 4, 1e-10, 1e-12, 1e-10)
    _, Y = ms.states_at(apart.points[:1], apart.T, ms.mesh[:-1] * apart.T)
    assert not in_phase_start(apart.system, ms, np.r_[ms.pack(Y, apart.T), 1.1275682582876292])
    branch = ssf.continue_orbit(apart, "eta", (1.1, 1.2), shooting="multiple", max_points=4)
    assert branch.values.size >= 2
    assert not [b for b in branch.bifurcations if b.kind == "symmetry-breaking"]
    gaps = [np.max(np.abs(p[:4] - p[4:8])) for p in branch.points]
    assert min(gaps) > 1e-2  # still apart: not projected onto the in-phase states
