"""Multiple shooting (issue 28, item 1): the periodic QR multipliers against analytic
products, multiple against single shooting where both converge, and multiple shooting
where single shooting stops, re-meshing against the fixed mesh, and an orbit of
multiplier 1e8 against the independent SciPy model, segment by segment. About 40 s warm."""

from __future__ import annotations

import dataclasses
import functools

import numpy as np
import pytest

import stickslip_fast as ssf
from stickslip_fast.bifurcation.multishoot import periodic_multipliers

# the stable period-1 orbit of Fig. 6 at eta = 2.0 (find_orbit, residual 2e-16)
Z_ETA2 = np.array([0.1115544410046177, 0.0, 0.12120838635656168, -0.00787487872112215])


def test_periodic_multipliers_resolve_graded_products():
    # A_i = P_i U_i P_{i-1}^T (P_i permutations, U_i upper triangular with the diagonal
    # 1e15, -2, 1e-15 and O(1) entries above it; P_{-1} = P_{m-1}), every factor exact
    # in floating point: the product over 20 factors is similar to U_19 ... U_0, whose
    # eigenvalues are the products of the diagonals: 1e300, 2^20 and 1e-300.
    rng = np.random.default_rng(1)
    k, m = 3, 20
    perms = [np.eye(k)[rng.permutation(k)] for _ in range(m)]
    factors = []
    for i in range(m):
        U = np.diag([1e15, -2.0, 1e-15]) + np.triu(rng.standard_normal((k, k)), 1)
        factors.append(perms[i] @ U @ perms[i - 1].T)
    mu = periodic_multipliers(factors)
    np.testing.assert_allclose(mu.real[:2], [1e300, 2.0**20], rtol=1e-10)
    # the smallest: its magnitude (QR of a graded matrix, as with single shooting)
    np.testing.assert_allclose(mu.real[2], 1e-300, rtol=0.1)
    np.testing.assert_array_equal(mu.imag, 0.0)
    # 1e20 per factor: the product (1e400) overflows, the multipliers below it do not
    factors[0] = factors[0] @ perms[-1] @ np.diag([1e100, 1.0, 1.0]) @ perms[-1].T
    mu = periodic_multipliers(factors)
    assert np.isinf(mu[0].real)
    np.testing.assert_allclose(mu[1].real, 2.0**20, rtol=1e-10)


def test_periodic_multipliers_of_rectangular_factors_and_complex_pairs():
    # n x k, n x n, k x n factors (the section's shape) and a rotation: compare with numpy
    rng = np.random.default_rng(2)
    factors = [
        rng.standard_normal((4, 3)),
        rng.standard_normal((4, 4)),
        rng.standard_normal((3, 4)),
    ]
    P = factors[2] @ factors[1] @ factors[0]
    ref = np.linalg.eigvals(P)
    ref = ref[np.argsort(-np.abs(ref), kind="stable")]
    np.testing.assert_allclose(periodic_multipliers(factors), ref, rtol=1e-12)
    th = 0.3
    R = 1.1 * np.array([[np.cos(th), -np.sin(th)], [np.sin(th), np.cos(th)]])
    mu = periodic_multipliers([R] * 7)
    np.testing.assert_allclose(
        np.sort(mu.imag), [-(1.1**7) * np.sin(7 * th), 1.1**7 * np.sin(7 * th)], rtol=1e-12
    )


@pytest.mark.parametrize("segments", [1, 3, 8])
def test_multiple_equals_single_shooting(segments):
    s = ssf.System.preset("asymmetric", eta=2.0)
    single = ssf.find_orbit(s, Z_ETA2, 1, tol=1e-13)
    multi = ssf.find_orbit(s, Z_ETA2 + 1e-4, 1, tol=1e-13, shooting="multiple", segments=segments)
    assert single.converged and multi.converged, (single, multi)
    np.testing.assert_allclose(multi.points, single.points, rtol=0, atol=1e-9)
    assert abs(multi.T - single.T) < 1e-9
    # the leading multiplier: the tangents' accuracy (~1e-9, docs/limits.md)
    assert abs(multi.multipliers[0] - single.multipliers[0]) < 1e-7
    np.testing.assert_allclose(np.linalg.eigvals(multi.jacobian).real.min(), -0.0968846, atol=1e-6)


def test_a_multiple_shooting_walk_keeps_single_shooting_s_pace():
    # With the defaults, Fig. 6's period-1 branch over eta 2 -> 3: single shooting takes
    # 24 points. Multiple shooting took 77 while its arclength measured T in time units
    # (dT/deta = 3.5 against 0.03 for the section point); with T / 2**k, 26.
    s = ssf.System.preset("asymmetric", eta=2.0)
    orbit = ssf.find_orbit(s, Z_ETA2, 1, tol=1e-12)
    kw = dict(stick_events=False, progress=False)
    single = ssf.continue_orbit(orbit, "eta", (2.0, 3.0), **kw)
    multi = ssf.continue_orbit(orbit, "eta", (2.0, 3.0), shooting="multiple", **kw)
    assert single.status == multi.status == "bounds", (single.status, multi.status)
    assert multi.values.size <= 1.25 * single.values.size, (multi.values.size, single.values.size)
    # the same curve: T and the point at the shared end agree
    assert abs(multi.T[-1] - single.T[-1]) < 1e-8
    np.testing.assert_allclose(multi.points[-1], single.points[-1], rtol=0, atol=1e-9)


def test_the_walk_s_coordinates_are_exact():
    # T scaled by a power of two: x -> x̃ -> x is exact, and the wrapped Jacobian is the
    # raw one with T's column divided by the scale (the chain rule, to the last bit)
    from stickslip_fast.bifurcation.multishoot_branch import _WalkCoordinates

    rng = np.random.default_rng(7)
    x0 = np.r_[rng.normal(size=9), 9.642944946320954, 2.0]
    DG = rng.normal(size=(10, 11))

    def evaluate(x):
        return True, x[:10] ** 2, DG, None

    walk = _WalkCoordinates(x0, evaluate, [(evaluate, 1e-10, 1e-8)], None, None)
    assert walk.scale == 0.125  # 2**-3: 9.64 is nearest 8
    xt = walk.to_walk(x0)
    assert xt[-2] == x0[-2] / 8 and np.array_equal(walk.from_walk(xt), x0)
    ok, G, DGt, _ = walk.evaluate(xt)
    assert ok and np.array_equal(G, x0[:10] ** 2)
    expected = DG.copy()
    expected[:, -2] = DG[:, -2] * 8
    assert np.array_equal(DGt, expected) and np.array_equal(DG[:, -2], evaluate(x0)[2][:, -2])
    _, _, DGr, _ = walk.refine[0][0](xt)
    assert np.array_equal(DGr, expected)


def test_bad_shooting_arguments_name_the_field():
    s = ssf.System.preset("asymmetric", eta=2.0)
    with pytest.raises(ValueError, match="shooting"):
        ssf.find_orbit(s, Z_ETA2, 1, shooting="double")
    with pytest.raises(ValueError, match="segments"):
        ssf.find_orbit(s, Z_ETA2, 1, shooting="multiple", segments=0)


# a point of the unstable side of Fig. 6's period-1 branch past its upper fold
# (3.3236646195), computed by the multiple-shooting continuation of docs/orbits.md:
# multiplier 1.13e8, far past where single shooting stops (~2.6e3, docs/limits.md)
ETA_UNSTABLE = 3.323525498113908
Z_UNSTABLE = np.array([0.07259589657661687, 0.0, 0.1221705830435874, -0.006666575275298541])
T_UNSTABLE = 14.043700862197168


# the start that converges onto it (from Z_UNSTABLE itself find_orbit ends "no-progress":
# at multiplier 1e8 the side of the stable manifold the start lies on decides)
START_UNSTABLE = Z_UNSTABLE + np.array([1e-9, 0.0, -1e-9, 1e-9])


@functools.cache
def unstable_orbit():
    """The orbit at ETA_UNSTABLE by multiple shooting (shared by the tests below, ~3.5 s).

    The first mesh follows the trajectory from the start, which leaves the orbit by
    1e-9 x 1e8 over the period, and the corrector takes about 30 damped steps to pull
    the segments in; how many depends on the CPU's roundings (30 on a Xeon, 31 on an
    AMD EPYC, which then ended "max-iter" at 1.02e-11 > tol under the old default of 30).
    The default for multiple shooting is now orbits.MS_MAX_ITER = 60: with the defaults
    the orbit is found.
    """
    s = ssf.System.preset("asymmetric", eta=ETA_UNSTABLE)
    return ssf.find_orbit(
        s, START_UNSTABLE, 1, shooting="multiple", tol=1e-11, rtol=1e-13, atol=1e-15
    )


def test_multiple_shooting_converges_where_single_shooting_stops():
    s = ssf.System.preset("asymmetric", eta=ETA_UNSTABLE)
    start = START_UNSTABLE
    single = ssf.find_orbit(s, start, 1, max_iter=8)
    assert not single.converged and single.status in ("no-progress", "max-iter"), single
    multi = unstable_orbit()
    assert multi.converged, multi
    # the continuation's point (corrected to tol 1e-12 there, at the same tolerances)
    np.testing.assert_allclose(multi.points[0], Z_UNSTABLE, rtol=0, atol=1e-10)
    assert abs(multi.T - T_UNSTABLE) < 1e-8
    assert 0.9e8 < abs(multi.multipliers[0]) < 1.4e8 and multi.multipliers[0].real > 1
    auto = ssf.find_orbit(s, start, 1, shooting="auto", tol=1e-11, rtol=1e-13, atol=1e-15)
    assert auto.converged and abs(auto.T - multi.T) < 1e-9

    # continued from there on its own segments (one trajectory from points[0] leaves the
    # orbit within the period: from it alone the start cannot be corrected)
    kw = dict(ds=1e-7, ds_max=1e-6, max_points=3, direction=-1, shooting="multiple",
              tol=1e-11, rtol=1e-13, atol=1e-15)  # fmt: skip
    mesh, starts = multi.segments
    assert mesh[0] == 0 and mesh[-1] == 1 and np.array_equal(starts[0], multi.points[0])
    with pytest.raises(ValueError, match="could not be corrected"):
        ssf.continue_orbit(dataclasses.replace(multi, segments=None), "eta", (3.3, 3.33), **kw)
    branch = ssf.continue_orbit(multi, "eta", (3.3, 3.33), **kw)
    assert branch.status == "max-points" and branch.values[0] == ETA_UNSTABLE
    assert np.all(np.diff(branch.values) < 0)
    np.testing.assert_allclose(branch.points[0], multi.points[0], rtol=0, atol=1e-10)
    mu = np.abs(branch.multipliers[:, 0])
    assert np.all(np.diff(mu) > 0) and 1e8 < mu[0] and mu[-1] < 2e8  # away from the fold
    # a point of it as an Orbit again, from its own segments (from its point alone,
    # find_orbit(shooting="multiple") cannot correct it: above)
    last = branch.orbit_at(-1, tol=1e-11, rtol=1e-13, atol=1e-15)
    assert last.converged and np.max(np.abs(last.points[0] - branch.points[-1])) < 1e-10
    assert abs(abs(last.multipliers[0]) / mu[-1] - 1) < 1e-6
    # each point is an orbit for multiple shooting on another mesh too (16 even cuts)
    for eta, z, T in zip(branch.values[1:], branch.points[1:], branch.T[1:]):
        other = ssf.find_orbit(s.replace(eta=float(eta)), z, 1, shooting="multiple",
                               segments=16, tol=1e-11, rtol=1e-13, atol=1e-15)  # fmt: skip
        assert other.converged and np.max(np.abs(other.points[0] - z)) < 1e-9, other
        assert abs(other.T - T) < 1e-9


def test_multiple_shooting_branch_points_are_fixed_points_of_the_return_map():
    from stickslip_fast.bifurcation.returnmap import return_map

    s = ssf.System.preset("asymmetric", eta=2.0)
    orbit = ssf.find_orbit(s, Z_ETA2, 1, tol=1e-12)
    # tol 1e-12: the default 1e-10 on the junctions leaves T free by tol / |v| along the
    # flow (measured: 2.2e-9 at a point corrected to 2.3e-11), more than the 1e-9 checked
    branch = ssf.continue_orbit(orbit, "eta", (1.9, 2.1), ds=0.01, ds_max=0.02, max_points=4,
                                shooting="multiple", stick_events=False, tol=1e-12)  # fmt: skip
    assert branch.values.size == 4 and branch.values[-1] > 2.0
    for eta, z, T, mu in zip(branch.values, branch.points, branch.T, branch.multipliers):
        st, pts, times, jac = return_map(s.replace(eta=float(eta)), z, 1)
        assert st == "ok" and np.max(np.abs(pts[-1] - z)) < 1e-9 and abs(times[-1] - T) < 1e-9
        assert abs(mu[0] - np.linalg.eigvals(jac)[np.argmax(np.abs(np.linalg.eigvals(jac)))]) < 1e-6


def test_a_remeshed_branch_keeps_to_the_orbits_of_the_fixed_mesh(monkeypatch):
    # a re-mesh forced at every point (limit 0.5: the stable orbit's segments amplify by
    # ~1): the walk goes on in pieces, each point re-sampled on the next mesh, corrected
    # and followed on; its points are the fixed-mesh branch's up to the first re-mesh
    # (the same calls) and fixed points of the return map (1e-9) after it
    from stickslip_fast.bifurcation import multishoot_branch
    from stickslip_fast.bifurcation.returnmap import return_map

    meshes = []
    remesh = multishoot_branch.remesh

    def counted(*args, **kw):
        mesh = remesh(*args, **kw)
        meshes.append(mesh.size - 1)
        return mesh

    monkeypatch.setattr(multishoot_branch, "REMESH_LIMIT", 0.5)
    monkeypatch.setattr(multishoot_branch, "remesh", counted)
    s = ssf.System.preset("asymmetric", eta=2.0)
    orbit = ssf.find_orbit(s, Z_ETA2, 1, tol=1e-12)
    kw = dict(ds=0.01, ds_max=0.02, max_points=4, shooting="multiple", stick_events=False,
              tol=1e-12)  # fmt: skip
    fixed = ssf.continue_orbit(orbit, "eta", (1.9, 2.1), **kw)
    branch = ssf.continue_orbit(orbit, "eta", (1.9, 2.1), remesh=True, **kw)
    assert meshes and branch.values.size == 4 and branch.values[-1] > 2.0, (meshes, branch)
    assert branch.values[1] == fixed.values[1] and np.array_equal(branch.points[1], fixed.points[1])
    assert not np.array_equal(branch.values[2:], fixed.values[2:])  # a piece on a new mesh
    for eta, z, T, mu in zip(branch.values, branch.points, branch.T, branch.multipliers):
        st, pts, times, jac = return_map(s.replace(eta=float(eta)), z, 1)
        assert st == "ok" and np.max(np.abs(pts[-1] - z)) < 1e-9 and abs(times[-1] - T) < 1e-9
        assert abs(mu[0] - np.linalg.eigvals(jac)[np.argmax(np.abs(np.linalg.eigvals(jac)))]) < 1e-6
    with pytest.raises(ValueError, match="remesh"):
        ssf.continue_orbit(orbit, "eta", (1.9, 2.1), remesh=True)


def test_find_orbit_max_segments_caps_the_bisection():
    # the orbit at mu = 1.1e8: 8 even cuts bisected to 14 segments by default, to exactly
    # 10 with max_segments=10; the same orbit (the multiplier from fewer, more amplifying
    # segments: 4e-4 relative, measured). Newton's residual on the 10 segments stalls at
    # the rounding noise their amplification leaves, 0.8-3.2e-11 (measured: it moved
    # within that range when the right-hand side's rounding changed), hence tol 1e-10
    s = ssf.System.preset("asymmetric", eta=ETA_UNSTABLE)
    full = unstable_orbit()
    capped = ssf.find_orbit(s, START_UNSTABLE, 1, shooting="multiple", tol=1e-10, rtol=1e-13,
                            atol=1e-15, max_segments=10)  # fmt: skip
    assert full.segments[0].size - 1 == 14 and capped.segments[0].size - 1 == 10
    assert capped.converged and np.max(np.abs(capped.points[0] - full.points[0])) < 1e-12
    assert abs(capped.multipliers[0] / full.multipliers[0] - 1) < 1e-3
    with pytest.raises(ValueError, match="max_segments must be an integer >= 8"):
        ssf.find_orbit(s, START_UNSTABLE, 1, shooting="multiple", max_segments=4)


def test_a_start_stalled_on_the_coarse_mesh_is_refined_and_corrected_there(monkeypatch):
    # The orbit at mu = 1.1e8 on its 14 segments: at rtol 1e-12 Newton stalls at its
    # rounding noise, 0.7-2e-11 (measured; once it reached 6.6e-13 by luck), far above
    # tol 1e-13; refined to 29 segments it gets to ~3e-15. The start is refined when it
    # stalls within COARSE_RES * tol, and the refined mesh must reach tol itself.
    from stickslip_fast.bifurcation import multishoot_branch as mb

    orbit = unstable_orbit()
    calls = []
    newton = mb.newton_multiple

    def spy(ms, u, tol, max_iter):
        out = newton(ms, u, tol, max_iter)
        calls.append((ms.mesh.size - 1, out[0], out[4]))
        return out

    monkeypatch.setattr(mb, "newton_multiple", spy)
    args = (orbit.system, orbit.points[0], orbit.T, "eta", 8, 1e-12, 1e-14, 1e-7, 1e-13, 10.0)
    x0, mesh = mb.ms_start(*args, known=orbit.segments)
    assert x0 is not None and mesh.size - 1 > 14, calls
    (n0, st0, res0), (n1, st1, res1) = calls
    assert n0 == 14 and st0 != "converged" and 1e-13 < res0 <= mb.COARSE_RES * 1e-13
    assert n1 == mesh.size - 1 and st1 == "converged" and res1 <= 1e-13
    calls.clear()
    monkeypatch.setattr(mb, "COARSE_RES", 1.0)  # the old rule: the coarse mesh must reach tol
    assert mb.ms_start(*args, known=orbit.segments)[0] is None and len(calls) == 1


def test_max_segments_caps_the_mesh_not_the_orbit(monkeypatch):
    # The orbit past the upper fold (mu = 1.1e8), found on 14 segments: the continuation
    # refines its mesh where a segment amplifies by more than MESH_LIMIT, to 29 segments by
    # default (measured), to exactly max_segments = 20 here, and finds the same orbits.
    from stickslip_fast.bifurcation import multishoot_branch

    orbit = unstable_orbit()
    kw = dict(ds=3e-5, ds_max=1e-3, max_points=3, direction=-1, shooting="multiple",
              tol=1e-12, rtol=1e-12, atol=1e-14, stick_events=False, sharp_ends=False)  # fmt: skip
    full = ssf.continue_orbit(orbit, "eta", (3.3, 3.33), **kw)
    capped = ssf.continue_orbit(orbit, "eta", (3.3, 3.33), max_segments=20, **kw)
    assert full.status == capped.status == "max-points", (full.status, capped.status)
    assert [seg[0].size - 1 for seg in full.segments] == [29] * 3
    assert [seg[0].size - 1 for seg in capped.segments] == [20] * 3
    np.testing.assert_allclose(capped.points[0], full.points[0], rtol=0, atol=1e-9)
    assert abs(capped.multipliers[0][0] / full.multipliers[0][0] - 1) < 1e-6
    with pytest.raises(ValueError, match="max_segments must be an integer >= 8"):
        ssf.continue_orbit(orbit, "eta", (3.3, 3.33), max_segments=4, **kw)  # segments: 8
    with pytest.raises(ValueError, match="max_segments"):
        ssf.continue_orbit(orbit, "eta", (3.3, 3.33), max_segments=True, **kw)

    # the re-mesh along the branch gets the cap too
    caps = []
    remesh = multishoot_branch.remesh

    def spy(*args, **kwargs):
        caps.append(kwargs.get("max_segments"))
        return remesh(*args, **kwargs)

    monkeypatch.setattr(multishoot_branch, "REMESH_LIMIT", 0.5)  # a re-mesh at every point
    monkeypatch.setattr(multishoot_branch, "remesh", spy)
    s = ssf.System.preset("asymmetric", eta=2.0)
    stable = ssf.find_orbit(s, Z_ETA2, 1, tol=1e-12)
    ssf.continue_orbit(stable, "eta", (1.9, 2.1), ds=0.01, ds_max=0.02, max_points=3,
                       shooting="multiple", stick_events=False, remesh=True, max_segments=9)  # fmt: skip
    assert caps and set(caps) == {9}, caps


def test_the_walk_on_from_single_shooting_does_not_turn_back():
    # Where single shooting stops at a fold it can cross it and crawl back within 1e-11 in
    # eta (k12 = -0.8316, eta = 2.5706), so neither the sign of its last step nor its
    # last tangent says which way is on. A probe decides by the leading multiplier: a
    # probe that moves it back towards its value WAY_BACK before the end turns back.
    from types import SimpleNamespace

    from stickslip_fast.bifurcation.multishoot import MESH_LIMIT
    from stickslip_fast.bifurcation.multishoot_branch import continue_multiple, ms_start
    from stickslip_fast.bifurcation.orbit_branch import WAY_BACK, _turns_back
    from stickslip_fast.bifurcation.walk_args import WalkSettings

    pts = np.array([[0.3, 0.0, 0.2, 0.0], [0.2, 0.0, 0.1, 0.0], [0.1, 0.0, 0.05, 0.0],
                    [0.1 + 1e-12, 0.0, 0.05, 0.0]])  # fmt: skip
    # came up to the fold (mu 0.5 -> 0.9), crossed it (1.0002) and crawled back (0.9995)
    came = SimpleNamespace(points=pts, values=np.array([2.2, 2.1, 2.0, 2.0 + 1e-12]),
                           multipliers=np.array([[0.5], [0.9], [1.0002], [0.9995]]))  # fmt: skip
    assert WAY_BACK > 1e-12

    def probe(mu):
        return SimpleNamespace(values=np.array([2.0, 2.0]), multipliers=np.array([[0.9995], [mu]]))

    assert _turns_back(came, probe(0.998))  # towards 0.9, the value before the crawl
    assert not _turns_back(came, probe(1.002))  # onwards, past the fold
    assert not _turns_back(came, probe(0.9995))  # not moved: the way on is kept
    # the probe's move counts from its own first point: multiple shooting's multiplier at
    # the branch's last point (0.9996) is offset from single shooting's (1.0004) by more
    # than the move onwards (+2e-4), as at k12 = -0.8316's upper fold
    past = SimpleNamespace(points=pts, values=came.values,
                           multipliers=np.array([[0.5], [0.9], [0.9990], [1.0004]]))  # fmt: skip
    onwards = SimpleNamespace(
        values=np.array([2.0, 2.0]), multipliers=np.array([[0.9996], [0.9998]])
    )
    assert not _turns_back(past, onwards)
    assert _turns_back(past, SimpleNamespace(values=np.array([2.0, 2.0]),
                                             multipliers=np.array([[0.9996], [0.9994]])))  # fmt: skip
    # on the model: with direction +1 in eta but a chord down in eta, the walk goes down
    s = ssf.System.preset("asymmetric", eta=2.0)
    orbit = ssf.find_orbit(s, Z_ETA2, 1, tol=1e-12)
    kw = dict(ds=0.01, ds_min=1e-8, ds_max=0.02, max_points=3, tol=1e-10, rtol=1e-11,
              atol=1e-13, fd_step=1e-7, stick_events=False, sharp_ends=False)  # fmt: skip
    x0, mesh = ms_start(s, orbit.points[0], orbit.T, "eta", 3, kw["rtol"], kw["atol"],
                        kw["fd_step"], kw["tol"], MESH_LIMIT)  # fmt: skip
    for chord, down in ((None, False), ((np.zeros(4), -1e-3), True)):
        br = continue_multiple(s, "eta", 1, x0, 1.0, (1.9, 2.1), WalkSettings(**kw),
                               segments=mesh, stages=(), chord=chord)  # fmt: skip
        assert br.values.size == 3 and (br.values[-1] < 2.0) == down, br.values


def test_a_re_sampled_point_is_integrated_at_its_own_parameter():
    # Re-meshing re-samples the last two points of a piece on the new mesh, integrating
    # each from its segment starts. It used to integrate them with the system of the
    # piece's first point: far along an unstable branch the re-sampled point then could
    # not be corrected and re-meshing silently fell back to the old mesh. Here the piece
    # has moved 0.012 in eta: re-sampled at its own eta, the point is already an orbit on
    # the new mesh, and correcting it moves it by no more than the tolerances.
    from stickslip_fast.bifurcation.arclength import pseudo_arclength
    from stickslip_fast.bifurcation.multishoot import MESH_LIMIT
    from stickslip_fast.bifurcation.multishoot_branch import (
        _resume,
        ms_evaluator,
        ms_start,
        multiplier_tests,
    )

    s = ssf.System.preset("asymmetric", eta=2.0)
    orbit = ssf.find_orbit(s, Z_ETA2, 1, tol=1e-12)
    rtol, atol, fd, tol = 1e-11, 1e-13, 1e-7, 1e-10
    x0, mesh = ms_start(s, orbit.points[0], orbit.T, "eta", 3, rtol, atol, fd, tol, MESH_LIMIT)
    evaluate, system_at, shooting_at = ms_evaluator(s, "eta", mesh, rtol, atol, fd)
    xs, _, _, status = pseudo_arclength(
        evaluate, x0, 1.0, (1.9, 2.1), ds=0.02, ds_min=1e-8, ds_max=0.05, max_points=3,
        tol=tol, tests=multiplier_tests, spectrum=periodic_multipliers,
    )  # fmt: skip
    assert status == "max-points" and xs[-1][-1] - x0[-1] > 0.005, (status, xs[:, -1])
    new_mesh = np.linspace(0.0, 1.0, 6)
    ev_new, _, shoot_new = ms_evaluator(s, "eta", new_mesh, rtol, atol, fd)
    ms_new = shoot_new(xs[-1][-1], None)
    x, chord = _resume(shooting_at(x0[-1], None), ms_new, ev_new, xs, tol, system_at)
    assert x is not None
    Y_old, T_old = shooting_at(xs[-1][-1], None).unpack(xs[-1][:-1])
    Y_new, T_new = ms_new.unpack(x[:-1])
    assert abs(x[-1] - xs[-1][-1]) < 1e-9 and abs(T_new - T_old) < 1e-9
    assert np.max(np.abs(Y_new[0] - Y_old[0])) < 1e-9


def test_re_meshing_reaches_orbits_that_the_fixed_mesh_cannot(monkeypatch):
    # The unstable side of Fig. 6's upper P1 fold from the orbit at multiplier 1.1e8, by
    # multiple shooting with the same start, bounds and settings, once on the mesh fixed
    # at the start and once re-meshed. Scaled down to take 24 points instead of minutes
    # (with the default limits the fixed mesh from here is still going, at 3e15, after
    # 40 points and ~1 min; tol 1e-11, rtol 1e-13, ds 1e-6):
    # the start's mesh is refined only until no segment amplifies by more than 1e4
    # (instead of MESH_LIMIT = 10; 18 segments, the largest 2.7e3) and re-meshing is
    # triggered at 1e5 (instead of REMESH_LIMIT = 100: the same factor 10 above it).
    # The fixed mesh then ends where its segment through the capture into the stick phase
    # amplifies too much; re-meshing cuts it and goes on.
    from stickslip_fast.bifurcation import multishoot_branch, orbit_branch
    from stickslip_fast.bifurcation.multishoot import MultiShooting, refine_mesh
    from stickslip_fast.bifurcation.returnmap import _field

    monkeypatch.setattr(orbit_branch, "MESH_LIMIT", 1e4)
    monkeypatch.setattr(multishoot_branch, "REMESH_LIMIT", 1e5)
    pieces = []
    walk = multishoot_branch.walk_pieces

    def spy(*args, **kw):  # keeps the pieces: their meshes and segment starts
        out = walk(*args, **kw)
        pieces.append(out[0])
        return out

    monkeypatch.setattr(multishoot_branch, "walk_pieces", spy)
    multi = unstable_orbit()
    kw = dict(ds=3e-5, ds_max=1e-3, max_points=24, direction=-1, shooting="multiple",
              tol=1e-12, rtol=1e-12, atol=1e-14, stick_events=False, sharp_ends=False)  # fmt: skip
    fixed = ssf.continue_orbit(multi, "eta", (3.3, 3.33), **kw)
    branch = ssf.continue_orbit(multi, "eta", (3.3, 3.33), remesh=True, **kw)
    mu_fixed = np.abs(fixed.multipliers[:, 0])
    mu = np.abs(branch.multipliers[:, 0])
    # the fixed mesh ends short of max_points (measured: 21 points, eta = 3.3234769588,
    # multiplier 7.2e12), the re-meshed branch does not (3.3234550959, 2.9e15)
    assert fixed.status in ("precision-limit", "step-too-small") and fixed.values.size < 24
    assert branch.status == "max-points" and branch.values.size == 24
    assert len(pieces[0]) == 1 and len(pieces[1]) >= 2  # the second one was re-meshed
    k = len(pieces[1][0].xs)  # up to the first re-mesh: the same calls, the same points
    np.testing.assert_array_equal(branch.values[:k], fixed.values[:k])
    assert np.all(np.diff(branch.values) < 0) and np.all(np.diff(mu) > 0)
    assert branch.values[-1] < fixed.values.min() - 1e-5
    assert mu_fixed.max() < 1e14 and mu[-1] > 20 * mu_fixed.max()

    # The far point checked by another integrator: its segment starts, each integrated
    # by simulate (Rodas5P, the trajectory kernel, not the variational one) over its
    # segment, join into a periodic orbit. Measured: 2.4e-13 (the corrector's tol is
    # 1e-12 with the other kernel); at the end point of 2026-11-26, 7.8e-13, and the same
    # starts at eta moved by 1e-10 left gaps of 1.8e-11, with T moved by 1e-9 3.3e-11:
    # the bound pins the orbit far below the 2.2e-5 in eta between the two ends.
    last = pieces[1][-1]
    x = last.xs[-1]
    assert x[-1] == branch.values[-1]
    system = multi.system.replace(eta=float(x[-1]))
    Y, T = last.ms.unpack(x[:-1])

    def flow(y, tau):
        res = ssf.simulate(system, tau, y0=y, rtol=1e-13, atol=1e-15, max_points=0)
        assert abs(res.t_final - tau) < 1e-12 and np.all(np.isfinite(res.final_state)), res
        return res.final_state

    taus = np.diff(last.ms.mesh) * T
    gaps = [np.max(np.abs(flow(Y[i], taus[i]) - Y[(i + 1) % len(taus)])) for i in range(len(taus))]
    assert max(gaps) < 1e-11
    # Its leading multiplier from central differences of simulate, segment by segment
    # (no variational equations), on the orbit cut finer (no segment amplifying more than
    # 10: on the branch's own mesh the segment through the capture amplified by 7e3 at
    # the end point of 2026-11-26, and differences of 1e-9 across it were not linear:
    # they gave 9.6e13 for 9.07e14), multiplied by the periodic QR scheme tested above.
    # Measured: 2.8901e15 against 2.8907e15 (2e-4; 30 segments).
    ms = MultiShooting(system, last.ms.mesh, 1e-12, 1e-14, 1e-12)
    fine = refine_mesh(ms, Y, T, limit=10.0)
    starts = []  # at the fine cuts, integrated from the start of the segment they cut
    for t in fine[:-1] * T:
        j = int(np.searchsorted(last.ms.mesh * T, t, side="right")) - 1
        dt = t - last.ms.mesh[j] * T
        starts.append(flow(Y[j], dt) if dt > 0 else Y[j])
    h, n = 1e-9, Y.shape[1]
    phis = []
    for y, tau in zip(starts, np.diff(fine) * T):
        cols = [(flow(y + h * e, tau) - flow(y - h * e, tau)) / (2 * h) for e in np.eye(n)]
        phis.append(np.array(cols).T)
    fine_ms = MultiShooting(system, fine, 1e-12, 1e-14, 1e-12)
    mu_fd = abs(periodic_multipliers(fine_ms.section_factors(phis, _field(system, Y[0])))[0])
    assert abs(mu_fd / mu[-1] - 1) < 1e-2


def test_an_appended_branch_does_not_locate_the_first_branch_s_fold_again():
    # shooting="auto" appends the multiple-shooting walk to the single-shooting branch;
    # at a sharp fold the two methods' multipliers differ by ~1e-4, so the walk can
    # locate the fold the first branch ended past once more, 3e-12 away: one fold.
    from stickslip_fast.bifurcation.branch import Bifurcation, Branch
    from stickslip_fast.bifurcation.multishoot_branch import append_branch

    s = ssf.System.preset("asymmetric", k12=-0.8316)

    def branch(values, bifs):
        n = len(values)
        return Branch(s, "eta", 1, np.array(values), np.zeros((n, 4)), np.full(n, 12.0),
                      np.ones((n, 3), complex), np.ones(n, bool),
                      [Bifurcation(k, v, i, np.zeros(5)) for k, v, i in bifs], "x")  # fmt: skip

    fold = 2.667348124830232
    first = branch([2.6673, fold, fold - 1e-12], [("fold", fold, 0)])
    second = branch([fold - 1e-12, fold - 2e-12, 2.6665],
                    [("fold", fold - 3e-12, 0), ("fold", 2.6666, 1)])  # fmt: skip
    joined = append_branch(first, second, "single shooting: precision-limit")
    assert [(b.kind, b.value, b.index) for b in joined.bifurcations] == [
        ("fold", fold, 0), ("fold", 2.6666, 3)]  # fmt: skip
    assert joined.values.size == 5


def test_joined_branches_keep_each_point_s_segments():
    # join_branches reverses the lower branch: its segments follow their points, and a
    # branch without segments (single shooting) gives None at its points
    from stickslip_fast.bifurcation.branch import Branch, join_branches

    s = ssf.System.preset("asymmetric")

    def branch(values, segments):
        n = len(values)
        pts = np.zeros((n, 4))
        pts[:, 0] = values
        return Branch(s, "eta", 1, np.array(values), pts, np.full(n, 12.0),
                      np.ones((n, 3), complex), np.ones(n, bool), [], "x",
                      segments=segments)  # fmt: skip

    seg = {v: (np.linspace(0, 1, 3), np.full((2, 4), v)) for v in (2.0, 1.9, 1.8)}
    lower = branch([2.0, 1.9, 1.8], [seg[2.0], seg[1.9], seg[1.8]])
    upper = branch([2.0, 2.1], None)
    joined = join_branches(lower, upper)
    assert joined.values.tolist() == [1.8, 1.9, 2.0, 2.1]
    assert [x if x is None else float(x[1][0, 0]) for x in joined.segments] == [
        1.8, 1.9, None, None]  # fmt: skip
    assert join_branches(branch([2.0, 1.9], None), upper).segments is None


def test_auto_goes_on_along_the_saddle_past_a_very_sharp_fold(tmp_path):
    # k12 = -0.8316, 1.1e-4 above where the period-1 region closes: the upper fold at
    # eta = 2.6673481247 is so sharp that single shooting stops within 1e-11 of it, with
    # mu = 1.0004 where multiple shooting gives 0.9996. "auto" goes on by multiple
    # shooting along the saddle (mu > 1, down in eta), not back along the stable branch
    # it came by (which it did while the probe compared the two methods' multipliers).
    y0 = [0.11834572437245043, 0.0, 0.1459190815849308, -0.008125583378266665]
    orbit = ssf.find_orbit(ssf.System.preset("asymmetric", eta=2.6, k12=-0.8316), np.array(y0), 1)
    br = ssf.continue_orbit(orbit, "eta", (2.5, 2.7), ds=1e-3, ds_max=5e-3, max_points=70,
                            shooting="auto", stick_events=False)  # fmt: skip
    assert "then multiple shooting" in br.status, br.status
    folds = [b for b in br.bifurcations if b.kind == "fold"]
    assert len(folds) == 1 and abs(folds[0].value - 2.6673481247) < 1e-9, folds
    # within ~1e-9 of the fold the walk wanders at the corrector's noise (measured: up to
    # 2e-10 either side of it, for 5-10 points); beyond, the saddle: mu grows from 1 to 59
    # while eta goes down, 4e-4 below the fold by point 70 (the walk that turned back had
    # mu falling to 0.005 there, on the stable branch)
    lead = np.max(np.abs(br.multipliers), axis=1)
    beyond = np.flatnonzero(br.values > folds[0].value - 1e-9)[-1] + 1
    last = slice(beyond, None)
    assert br.values.size - beyond >= 20, br.values - folds[0].value
    assert np.all(np.diff(lead[last]) > 0) and np.all(np.diff(br.values[last]) < 0)
    assert lead[-1] > 20 and br.values[-1] < folds[0].value - 3e-4, (lead[-1], br.values[-1])
    # the segments of every point found by multiple shooting, None where single shooting
    # found it; each (mesh, starts) starts at the point and re-converges where it is
    n_single = next(i for i, seg in enumerate(br.segments) if seg is not None)
    assert len(br.segments) == br.values.size and 0 < n_single < br.values.size - 30
    assert all(seg is None for seg in br.segments[:n_single])
    for i in (n_single + 1, br.values.size - 1):
        mesh, starts = br.segments[i]
        assert mesh[0] == 0 and mesh[-1] == 1 and starts.shape == (mesh.size - 1, 4)
        assert np.array_equal(starts[0], br.points[i])
    # orbit_at: the end (mu = 59) corrected again on its own segments, and the start by
    # single shooting from its point
    end = br.orbit_at(-1)
    assert end.converged and end.segments is not None and end.system.eta == br.values[-1]
    assert np.max(np.abs(end.points[0] - br.points[-1])) < 1e-9 and abs(end.T - br.T[-1]) < 1e-9
    assert abs(end.multipliers[0] - br.multipliers[-1][0]) < 1e-6 * lead[-1]
    first = br.orbit_at(0)
    assert first.converged and first.segments is None
    assert np.max(np.abs(first.points[0] - br.points[0])) < 1e-9
    with pytest.raises(ValueError, match="i must index"):
        br.orbit_at(br.values.size)
    # the segments travel with the branch file (a collaborator can correct a far point)
    back = ssf.Branch.from_hdf5(br.to_hdf5(tmp_path / "saddle.h5"))
    assert [x is None for x in back.segments] == [x is None for x in br.segments]
    for a, b in zip(back.segments[n_single:], br.segments[n_single:]):
        assert np.array_equal(a[0], b[0]) and np.array_equal(a[1], b[1])
    again = back.orbit_at(-1)
    assert again.converged and np.array_equal(again.points[0], end.points[0])


def test_multiple_shooting_orbit_against_independent_scipy_segments():
    # The orbit of multiplier 1.1e8 checked segment by segment by the independent SciPy
    # model (tests/reference/scipy_segments.py: Radau with its variational equations,
    # the leading multiplier by orthogonal iteration, no product formed). Over the whole
    # period no integrator can follow it (1e8 x 1e-16 would be the best case), but each
    # segment can be: the junctions close to 1e-12 and the multipliers agree to 1e-4.
    import sys
    from pathlib import Path

    sys.path.insert(0, str(Path(__file__).resolve().parent / "reference"))
    import scipy_segments as sg

    o = unstable_orbit()
    mesh, starts = o.segments
    p = {**o.system.to_dict(), "n_oscillators": o.system.n_oscillators}
    ref = sg.check_segments(p, mesh, starts, o.T)
    assert ref["residual"] < 1e-10, ref["residuals"]
    assert abs(ref["mu1"] / abs(o.multipliers[0]) - 1) < 1e-4, (ref["mu1"], o.multipliers[0])
    # the check can fail: one segment's start moved by 1e-8 along the segment's most
    # amplified direction (it amplifies by ~2e7 here) breaks its junction
    k = int(np.argmax(ref["norms"]))
    assert ref["norms"][k] > 1e6
    v = np.linalg.svd(ref["factors"][k])[2][0]
    y1, _ = sg.flow_segment(p, starts[k] + 1e-8 * v, (mesh[k + 1] - mesh[k]) * o.T)
    assert np.max(np.abs(y1 - starts[(k + 1) % (mesh.size - 1)])) > 1e-3
