"""Branch points: where a second branch of solutions crosses the one being followed.

The test function is det [DG; tᵀ] (rows scaled); it is checked on maps whose branch
points are known in closed form (a pitchfork and a transcritical bifurcation of a map's
fixed points, a fold that must stay a fold), on a map whose Jacobian has a second, tiny
singular value (no label is read from its noisy tangent), and on the engine's anti-phase
branch of two disks on one motor, against the multipliers of find_orbit.
"""

from __future__ import annotations

import numpy as np
import pytest

import stickslip_fast as ssf
from stickslip_fast.bifurcation.arclength import STALL_WINDOW, pseudo_arclength
from stickslip_fast.bifurcation.detection import (
    RANK_GAP_MIN,
    branch_point_test,
    rank_gap,
    singular_gaps,
)
from stickslip_fast.bifurcation.walk_args import BRANCH_POINT_DS

KW = dict(ds=0.05, ds_min=1e-6, ds_max=0.1, max_points=200, tol=1e-12, branch_points=True)


def pitchfork_map(x):
    # P(z; lam) = (z1 + z1 (lam - z1^2), z2 / 2): the fixed points z1 = 0 (multiplier
    # 1 + lam) and z1^2 = lam (multiplier 1 - 2 lam) cross at the pitchfork lam = 0
    z1, z2, lam = x
    A = np.diag([1 + lam - 3 * z1 * z1, 0.5])
    G = np.array([z1 * (lam - z1 * z1), -0.5 * z2])
    return True, G, np.hstack([A - np.eye(2), np.array([[z1], [0.0]])]), A


def transcritical_map(x):
    # P(z; lam) = (z1 + z1 (lam - z1), z2 / 2): the fixed points z1 = 0 and z1 = lam
    # exchange stability at lam = 0
    z1, z2, lam = x
    A = np.diag([1 + lam - 2 * z1, 0.5])
    G = np.array([z1 * (lam - z1), -0.5 * z2])
    return True, G, np.hstack([A - np.eye(2), np.array([[z1], [0.0]])]), A


def fold_map(x):
    # P(z; lam) = (z1 + lam - z1^2, z2 / 2): a fold at lam = 0, no other branch
    z1, z2, lam = x
    A = np.diag([1 - 2 * z1, 0.5])
    G = np.array([lam - z1 * z1, -0.5 * z2])
    return True, G, np.hstack([A - np.eye(2), np.array([[1.0], [0.0]])]), A


def kinds(bifs):
    return [b[0] for b in bifs]


def test_the_trivial_branch_marks_the_pitchfork():
    xs, mults, bifs, status = pseudo_arclength(
        pitchfork_map, np.array([0.0, 0.0, -0.47]), 1.0, (-0.5, 0.5), **KW
    )
    assert status == "bounds" and kinds(bifs) == ["branch-point"]
    kind, lam, idx, x = bifs[0]
    assert abs(lam) < 1e-9 and np.max(np.abs(x[:2])) < 1e-12
    # the multiplier 1 + lam passes +1 there, with no fold: the other tests stay silent
    assert mults[idx, 0].real < 1 < mults[idx + 1, 0].real
    # without the test the stability changes with no label at all (as before it existed)
    _, _, bifs0, _ = pseudo_arclength(
        pitchfork_map,
        np.array([0.0, 0.0, -0.47]),
        1.0,
        (-0.5, 0.5),
        **dict(KW, branch_points=False),
    )
    assert bifs0 == []


def test_the_side_branch_turns_at_the_pitchfork_and_is_not_called_a_fold():
    start = np.array([0.5, 0.0, 0.25])
    xs, _, bifs, status = pseudo_arclength(pitchfork_map, start, -1.0, (-0.5, 0.5), **KW)
    assert status == "bounds"
    assert kinds(bifs) == ["branch-point"]  # not "fold", though lambda turns there
    # G is quadratic in the distance from a branch point: with tol 1e-12 the point is
    # fixed only to ~sqrt(tol) (measured: lambda 1.8e-6, z1 1.7e-7)
    assert abs(bifs[0][1]) < 1e-5 and abs(bifs[0][3][0]) < 1e-5
    np.testing.assert_allclose(xs[:, 0] ** 2, xs[:, 2], atol=1e-10)
    assert xs[-1, 0] < -0.5  # it went on through the point, to the other half


def test_the_transcritical_point_is_marked_on_both_branches():
    for start in ([0.0, 0.0, -0.47], [-0.47, 0.0, -0.47]):
        xs, mults, bifs, status = pseudo_arclength(
            transcritical_map, np.array(start), 1.0, (-0.5, 0.5), **KW
        )
        assert status == "bounds" and kinds(bifs) == ["branch-point"]
        assert abs(bifs[0][1]) < 1e-9
        idx = bifs[0][2]
        # the two branches exchange stability there
        assert (abs(mults[idx, 0]) - 1) * (abs(mults[idx + 1, 0]) - 1) < 0


def test_a_fold_stays_a_fold():
    xs, _, bifs, status = pseudo_arclength(
        fold_map, np.array([0.5, 0.0, 0.25]), -1.0, (-1.0, 1.5), **KW
    )
    assert status == "bounds" and kinds(bifs) == ["fold"] and abs(bifs[0][1]) < 1e-8
    # det [DG; t] keeps its sign through the fold, at a distance from 0
    _, _, DG, _ = fold_map(bifs[0][3])
    t = np.array([1.0, 0.0, 0.0])
    assert abs(branch_point_test(DG, t)) == pytest.approx(1.0)


def test_no_fold_is_read_from_a_tangent_that_is_noise():
    # a second fixed-point direction whose residual is eps (z2 - z1): DG's smallest
    # singular value is eps sqrt(3/2) (DG DG^T = [[2, eps], [eps, 2 eps^2]]), and where it is
    # below RANK_GAP_MIN times the largest the tangent is noise: no label is read from it
    def nearly_neutral(eps):
        def evaluate(x):
            z1, z2, lam = x
            G = np.array([lam - z1 * z1, eps * (z2 - z1)])
            DG = np.array([[-2 * z1, 0.0, 1.0], [-eps, eps, 0.0]])
            return True, G, DG, DG[:, :2] + np.eye(2)

        return evaluate

    start = np.array([0.5, 0.5, 0.25])
    _, _, DG, _ = nearly_neutral(1e-9)(start)
    assert rank_gap(DG) == pytest.approx(1e-9 * np.sqrt(3.0) / 2.0, rel=1e-6)
    kw = dict(KW, noise_gap=RANK_GAP_MIN)  # as orbit branches have it
    xs, _, bifs, status = pseudo_arclength(nearly_neutral(1e-3), start, -1.0, (-1.0, 1.5), **kw)
    assert status == "bounds" and kinds(bifs) == ["fold"] and abs(bifs[0][1]) < 1e-8
    assert 1e-3 * np.sqrt(3.0) / 2.0 > RANK_GAP_MIN
    xs, _, bifs, status = pseudo_arclength(nearly_neutral(1e-9), start, -1.0, (-1.0, 1.5), **kw)
    assert xs[:, 0].min() < 0 < xs[:, 0].max()  # the walk passed the turn, unlabelled
    assert bifs == []
    # and, the gap below the noise at STALL_WINDOW points in a row (here every point:
    # the solutions form a surface within tol / eps), it stops and says why
    assert status == "degenerate" and len(xs) == STALL_WINDOW
    # with the rule off (the default of pseudo_arclength) the same turn is read as a fold
    _, _, bifs, _ = pseudo_arclength(nearly_neutral(1e-9), start, -1.0, (-1.0, 1.5), **KW)
    assert kinds(bifs) == ["fold"]


def test_one_huge_multiplier_is_not_a_degenerate_family():
    # past a sharp fold one multiplier grows to 1e6 and more: DG's largest singular value
    # with it, so the rank gap falls below RANK_GAP_MIN (6e-8 measured on Fig. 12's period-2
    # branch) although DG has no second null direction. Here G = (K (z1 - lam), z2 - z1,
    # z3 - z2) with K = 1e8: a straight branch, rank gap ~1e-8, the smallest singular value
    # against the next ~0.4: the walk must go on to its bound, not end "degenerate"
    K = 1e8

    def stiff(x):
        z1, z2, z3, lam = x
        G = np.array([K * (z1 - lam), z2 - z1, z3 - z2])
        DG = np.array([[K, 0.0, 0.0, -K], [-1.0, 1.0, 0.0, 0.0], [0.0, -1.0, 1.0, 0.0]])
        return True, G, DG, DG[:, :3] + np.eye(3)

    _, _, DG, _ = stiff(np.zeros(4))
    first, second = singular_gaps(DG)
    s = np.linalg.svd(DG, compute_uv=False)
    assert first == pytest.approx(s[-1] / s[0]) and first < 1e-8 < RANK_GAP_MIN
    assert second == pytest.approx(s[-1] / s[-2]) and second > 0.1
    kw = dict(KW, tol=1e-6, noise_gap=RANK_GAP_MIN)
    xs, _, bifs, status = pseudo_arclength(stiff, np.zeros(4), 1.0, (-1.0, 1.0), **kw)
    assert status == "bounds" and xs[-1, -1] == pytest.approx(1.0) and len(xs) > STALL_WINDOW
    assert bifs == []


# --------------------------------------------------------------- on the engine
def _anti_phase(eta: float, point: list[float]) -> ssf.Orbit:
    # Figs. 14-15: two disks of the symmetric set on one motor; the paper's start (disk 2
    # displaced) settles at eta = 3 on this orbit, disk 2 about half a period behind disk 1
    system = ssf.System.preset("symmetric", drive="dc-motor", n_oscillators=2, eta=eta)
    orbit = ssf.find_orbit(system, np.array(point))
    assert orbit.converged and orbit.period == 1
    return orbit


def _leading_real(orbit: ssf.Orbit) -> float:
    mu = orbit.multipliers
    return float(mu[np.argmin(np.abs(mu - 1.0))].real)


@pytest.fixture(scope="module")
def anti_branch():
    # from its point at eta = 1.7202 (a branch walked down from the paper's start at eta = 3)
    start = _anti_phase(1.7202475596551963, [0.012102199873405984, 0.0, 0.0, 0.0,
                        0.06455177287803203, 0.009646957844271574, 0.0, 0.0,
                        0.009650344399020629])  # fmt: skip
    return start, ssf.continue_orbit(start, "eta", (1.35, 1.8), direction=-1)


def test_the_anti_phase_branch_has_two_branch_points(anti_branch):
    start, branch = anti_branch
    bps = [b for b in branch.bifurcations if b.kind == "branch-point"]
    assert [b.label for b in bps] == ["BP", "BP"]
    assert not [b for b in branch.bifurcations if b.kind == "fold"]
    # find_orbit's multiplier (rtol 1e-12) passes 1 at 1.57269836 (a secant to 1e-10 in mu)
    # and at 1.41183 (0.776 at 1.4116, 0.972 at 1.4118: dmu/deta ~ 1e3). The second is
    # sharp: its side branch is 4e-5 away 8e-5 past it, and the locator's trials land on
    # either (measured 1.4118317 walked from eta = 3, 1.4118753 from here). G is quadratic
    # near a branch point: located to ~sqrt(tol) (measured 2.6e-7 off at the first)
    assert abs(bps[0].value - 1.57269836) < 1e-6 and abs(bps[1].value - 1.41183) < 1e-4
    # the reference: find_orbit on both sides of the first point, 1e-3 away: a real
    # multiplier passes +1 (past the second, find_orbit finds the side branch: stable, the
    # pitchfork is supercritical)
    for d in (-1e-3, 1e-3):
        orbit = ssf.find_orbit(start.system.replace(eta=bps[0].value + d), bps[0].point)
        assert orbit.converged and (_leading_real(orbit) > 1.0) is (d < 0)
    assert branch.stable[bps[0].index] and not branch.stable[bps[0].index + 1]
    assert not branch.stable[bps[1].index] and branch.stable[bps[1].index + 1]


def test_no_folds_are_read_where_a_disk_is_nearly_undamped(monkeypatch):
    # lower down, disk 2's oscillation shrinks to nearly undamped steady sliding (no
    # viscous damping, c = 0: the sliding equilibrium's eigenvalues are -2.6e-6 +- i at
    # eta = 1.1): a multiplier tends to 1 (1 - 2e-6 at 1.06), DG's second singular value
    # falls to 1e-8 of its largest, near its noise (rtol 1e-11 against 1e-12: 7e-9 at
    # 1.028), and the walk zig-zags within 3e-5 of eta = 1.02404
    start = _anti_phase(1.1275682582876292, [0.03734505165096868, 0.0, 0.0, 0.0,
                        0.060820214617317424, 0.0009027951066187418, 0.0, 0.0,
                        0.00979440927478325])  # fmt: skip
    kw = dict(direction=-1, max_points=100, stick_events=False)
    branch = ssf.continue_orbit(start, "eta", (1.0, 1.2), **kw)
    # it ends there, "degenerate", after STALL_WINDOW points with the gap below the noise
    # (measured: 15 points, the last five at eta = 1.024101-1.024222; before the rule it
    # walked on to max_points along the family, eta wiggling within 1.5e-4)
    assert branch.status == "degenerate" and branch.bifurcations == []
    assert STALL_WINDOW <= len(branch.values) < 30
    # (the noise decides where along that stretch: 1.024101-1.024222 on a Xeon,
    # 1.024065-1.024753 on an AMD EPYC VM)
    assert 1.024 < branch.values[-5:].min() and branch.values[-5:].max() < 1.025
    # the same walk reading its tangent everywhere reports bifurcations there, none of
    # them the system's: which kind the noise gives depends on the CPU's roundings
    # (13 folds with 200 points on a Xeon; 3 branch points at 1.024065-1.024133 on an
    # AMD EPYC VM, where it ended "step-too-small" after 27 points)
    monkeypatch.setattr("stickslip_fast.bifurcation.orbit_record.RANK_GAP_MIN", 0.0)
    noisy = ssf.continue_orbit(start, "eta", (1.0, 1.2), **kw)
    spurious = [b.value for b in noisy.bifurcations if b.kind in ("fold", "branch-point")]
    assert len(spurious) >= 3 and max(spurious) - min(spurious) < 1e-4


def test_switching_at_a_branch_point_finds_the_crossing_branch(anti_branch):
    start, branch = anti_branch
    bp = next(b for b in branch.bifurcations if b.kind == "branch-point")
    orbit = ssf.switch_branch(branch, bp)  # the defaults: 1e-4 wins (smaller are too flat)
    assert orbit.converged and orbit.period == 1
    eta = orbit.system.eta
    assert abs(eta - bp.value) < 1e-4  # measured 8.5e-6
    # the reference: the anti-phase orbit at the same eta (find_orbit from the branch
    # point): the switched orbit is another one, about the offset away
    same = ssf.find_orbit(orbit.system, bp.point)
    assert same.converged
    gap = np.max(np.abs(orbit.points[0] - same.points[0]))
    assert 5e-5 < gap < 2e-4  # measured 1.0e-4
    # and it is a fixed point of the map at its eta to the corrector's tolerance
    assert orbit.residual < 1e-9
    # the normal form of a pitchfork: the side branch lies on the side where the anti-phase
    # orbit is stable (above the point) and is unstable there (subcritical), 1 + O(eta - bp)
    # With the defaults: the switched orbit's origin gives the first step BRANCH_POINT_DS
    # and the direction (up). A first step of 0.01 went back onto the stable anti-phase
    # branch on an AMD EPYC VM (multiplier 0.66 at 1.5756): the crossing branch's tangent
    # turns from 0.15 to 0.998 in eta within 1e-3 of arclength.
    assert orbit.origin is bp and orbit.origin_param == "eta"
    side = ssf.continue_orbit(orbit, "eta", (1.35, 1.8), stick_events=False)
    assert side.points.shape[0] > 2 and abs(side.values[1] - side.values[0]) < BRANCH_POINT_DS
    assert side.status == "bounds" and side.values[-1] == 1.8
    assert np.all(side.values > bp.value) and not np.any(side.stable)
    lead = np.abs(side.multipliers[:, 0])
    assert lead[0] < 1.01  # measured 1.0008
    # unstable all the way to the bound, where it ends on this sheet: the branch turns at
    # a fold at eta = 1.951 and comes back stable 8.5e-4 away (in x2 - x1), and ending
    # on the bound with eta fixed from the full step's predictor once landed there
    # (multiplier 0.63, and a spurious branch point at 1.79392 between the two sheets)
    assert np.all(np.diff(lead) > 0) and not side.bifurcations
    assert abs(lead[-1] - 1.4496) < 2e-3  # a walk with steps of 0.004 passes 1.4474, 1.4552
    with pytest.raises(ValueError, match="branch point"):
        ssf.switch_branch(branch, ssf.Bifurcation("fold", bp.value, bp.index, bp.point))
