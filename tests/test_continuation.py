"""Pseudo-arclength continuation (issue 10, section 3).

The core is checked on maps whose bifurcations are known in closed form (a fold and a
period-doubling of z -> z + lambda - z^2, a Neimark-Sacker point of z -> lambda R z); the
orbit continuation against brute-force simulation of the engine. About 10 s warm.
"""

from __future__ import annotations

import dataclasses
import math
import zlib

import numpy as np
import pytest

import stickslip_fast as ssf
from stickslip_fast.bifurcation.continuation import (
    NOISE_FLOOR,
    Branch,
    _correct,
    continue_orbit,
    period_doubling_start,
    pseudo_arclength,
)

KW = dict(ds=0.05, ds_min=1e-6, ds_max=0.1, max_points=200, tol=1e-12)


def fold_pd_map(x):
    # P(z; lam) = (z1 + lam - z1^2, z2 / 2): fixed points z1 = +-sqrt(lam), multiplier 1 - 2 z1:
    # a fold at lam = 0 (z1 = 0, multiplier +1), a period-doubling at lam = 1 (z1 = 1, -1)
    z1, z2, lam = x
    A = np.diag([1 - 2 * z1, 0.5])
    G = np.array([lam - z1 * z1, -0.5 * z2])
    return True, G, np.hstack([A - np.eye(2), np.array([[1.0], [0.0]])]), A


def ns_map(x, th=0.7):
    # P(z; lam) = lam R(th) z: multipliers lam exp(+-i th), a Neimark-Sacker point at lam = 1
    z, lam = x[:2], x[2]
    R = np.array([[np.cos(th), -np.sin(th)], [np.sin(th), np.cos(th)]])
    A = lam * R
    return True, A @ z - z, np.hstack([A - np.eye(2), (R @ z)[:, None]]), A


def test_fold_is_passed_and_the_branch_returns_on_the_unstable_side():
    xs, mults, bifs, status = pseudo_arclength(
        fold_pd_map, np.array([0.5, 0.0, 0.25]), -1.0, (-1.0, 1.5), **KW
    )
    assert status == "bounds"
    assert [b[0] for b in bifs] == ["fold"]
    kind, lam, idx, x = bifs[0]
    assert abs(lam) < 1e-8 and abs(x[0]) < 1e-6
    # after the fold lambda grows again, on z1 = -sqrt(lam) with multiplier 1 - 2 z1 > 1
    assert xs[-1, 0] < -1.0 and xs[-1, 2] > 1.0
    np.testing.assert_allclose(xs[:, 0] ** 2, xs[:, 2], atol=1e-10)
    after = xs[idx + 1 :, 0]
    assert np.all(after < 0) and np.all(np.abs(mults[idx + 1 :, 0]) > 1)


def test_tighter_stages_pass_a_fold_the_first_evaluator_cannot_resolve():
    """``refine``: where the corrector fails at ds_min, go on with the next evaluator."""

    def blind(x):  # cannot evaluate near the fold (wider than ds_max), like a too-loose tol
        return (False, *fold_pd_map(x)[1:]) if abs(x[0]) < 0.2 else fold_pd_map(x)

    start = np.array([0.5, 0.0, 0.25])
    kw = dict(KW, ds_min=1e-4)
    xs, _, bifs, status = pseudo_arclength(blind, start, -1.0, (-1.0, 1.5), **kw)
    assert status == "step-too-small" and not bifs and np.all(xs[:, 0] > 0)
    xs, mults, bifs, status = pseudo_arclength(
        blind, start, -1.0, (-1.0, 1.5), refine=[(fold_pd_map, 1e-12, 1e-8)], **kw
    )
    assert status == "bounds" and [b[0] for b in bifs] == ["fold"]
    assert abs(bifs[0][1]) < 1e-8
    assert xs[-1, 0] < -1.0 and np.abs(mults[-1, 0]) > 1
    np.testing.assert_allclose(xs[:, 0] ** 2, xs[:, 2], atol=1e-10)


def test_a_stopped_walk_resumes_in_new_coordinates_through_the_fold():
    """``stop`` and ``orient`` (re-meshed multiple shooting): a walk stopped past the fold
    resumes in rescaled coordinates (w = 2 z1) along the branch, not back to the fold."""

    def scaled(x):  # the same map in w = 2 z1: G(w, z2, lam) = G(w / 2, z2, lam)
        ok, G, DG, A = fold_pd_map(np.array([0.5 * x[0], x[1], x[2]]))
        return ok, G, DG @ np.diag([0.5, 1.0, 1.0]), A

    def stop(x, A, walk):  # the first point past the fold with z1 < -0.3
        return x[0] < -0.3

    start = np.array([0.5, 0.0, 0.25])
    xs, _, bifs, status = pseudo_arclength(fold_pd_map, start, -1.0, (-1.0, 1.5), stop=stop, **KW)
    assert status == "stopped" and [b[0] for b in bifs] == ["fold"] and xs[-1, 0] < -0.3
    new = xs[-2:] * np.array([2.0, 1.0, 1.0])
    chord = new[1] - new[0]  # lambda grows there: direction=-1 alone would turn back
    assert chord[-1] > 0
    back, _, _, st_back = pseudo_arclength(scaled, new[1], -1.0, (-1.0, 1.5), **KW)
    assert back[1, 2] < new[1, 2]
    ys, mults, bifs2, st = pseudo_arclength(scaled, new[1], -1.0, (-1.0, 1.5), orient=chord, **KW)
    assert st == "bounds" and not bifs2 and abs(ys[-1, 2] - 1.5) < 1e-12
    np.testing.assert_allclose((0.5 * ys[:, 0]) ** 2, ys[:, 2], atol=1e-10)
    assert np.all(np.diff(ys[:, 2]) > 0) and np.all(np.abs(mults[:, 0]) > 1)


def test_period_doubling_is_located():
    xs, mults, bifs, status = pseudo_arclength(
        fold_pd_map, np.array([0.5, 0.0, 0.25]), 1.0, (-1.0, 1.5), **KW
    )
    assert [b[0] for b in bifs] == ["period-doubling"]
    assert abs(bifs[0][1] - 1.0) < 1e-8
    i = bifs[0][2]
    assert mults[i, 0].real > -1 > mults[i + 1, 0].real


def test_neimark_sacker_is_located():
    xs, mults, bifs, status = pseudo_arclength(ns_map, np.array([0.0, 0.0, 0.5]), 1.0, (0.0, 2.0), **KW)  # fmt: skip
    assert [b[0] for b in bifs] == ["neimark-sacker"]
    assert abs(bifs[0][1] - 1.0) < 1e-8


EPS = np.finfo(float).eps


def _noise(x, amplitude):
    # deterministic, zero-mean "evaluation noise": a function of x's bits, like the
    # integration's (the same x gives the same value, a neighbouring x an unrelated one)
    return amplitude * (2.0 * zlib.crc32(x.tobytes()) / 2**32 - 1.0)


def steep_fold_map(x, k=30.0, count=None):
    # G1 = (lam - z1^2) exp(-k z1): the fold of fold_pd_map at lam = 0 (same fixed points
    # z1 = +-sqrt(lam)), but on the unstable side the multiplier 1 + 2 |z1| exp(k |z1|)
    # grows exponentially, like the saddle orbits past Fig. 6's folds. Each evaluation
    # carries noise of 0.3 eps ||DG|| ||x||, as measured on those (docs/orbits.md, "Cost").
    if count is not None:
        count.append(1)
    z1, z2, lam = x
    w = math.exp(-k * z1)
    g = lam - z1 * z1
    g_z = (-2.0 * z1 - k * g) * w
    DG = np.array([[g_z, 0.0, w], [0.0, -0.5, 0.0]])
    floor = EPS * np.abs(DG).sum(axis=1).max() * np.abs(x).max()
    G = np.array([g * w + _noise(x, 0.3 * floor), -0.5 * z2])
    return True, G, DG, np.diag([1.0 + g_z, 0.5])


def test_the_corrector_stops_at_the_round_off_floor():
    """Where eps ||DG|| ||x|| exceeds tol, Newton stops when its update is below tol."""
    lam = 0.25  # unstable fixed point z1 = -0.5, multiplier 1 + exp(15) = 3.3e6
    e_lam = np.array([0.0, 0.0, 1.0])
    count = []
    x_pred = np.array([-0.5 + 1e-8, 0.0, lam])
    ok, x, data, _ = _correct(lambda x: steep_fold_map(x, count=count), x_pred, e_lam, x_pred,
                              1e-12, 6)  # fmt: skip
    # the floor (~1e-9) is above tol: no evaluation meets tol, and the plain test would
    # spend all 7; stopped once the update is below tol and the residual no longer
    # halves (here at the 4th), at the analytic root
    assert not ok and data is NOISE_FLOOR and len(count) < 7
    assert abs(x[0] + 0.5) <= 1e-12 and x[2] == lam
    # on fold_pd_map (the same fixed point, no noise, multiplier 2) it meets tol
    ok, x, _, _ = _correct(fold_pd_map, x_pred, e_lam, x_pred, 1e-12, 6)
    assert ok and abs(x[0] + 0.5) <= 1e-12


def test_the_corrector_gives_up_when_noise_stalls_it():
    """Noise far above the round-off floor (as near a sharp fold): two iterations without
    halving the residual, in Newton's local regime, end the corrector."""

    def noisy_linear(x):  # G = z - (0.3, -0.2) plus noise 1e-9; root at the analytic point
        count.append(1)
        DG = np.hstack([np.eye(2), np.zeros((2, 1))])
        G = x[:2] - np.array([0.3, -0.2]) + _noise(x, 1e-9)
        return True, G, DG, np.zeros((2, 2))

    count = []
    e_lam = np.array([0.0, 0.0, 1.0])
    x_pred = np.array([0.31, -0.19, 1.0])
    ok, x, data, _ = _correct(noisy_linear, x_pred, e_lam, x_pred, 1e-12, 6)
    assert not ok and data is None and len(count) < 7
    np.testing.assert_allclose(x[:2], [0.3, -0.2], atol=2e-9)


def test_a_branch_ends_at_the_precision_limit_of_a_noisy_map():
    """End to end: the steep fold is passed and located, the unstable side followed
    until the analytic round-off floor passes tol, and the end is "precision-limit"."""
    count = []
    tol = 1e-12
    xs, mults, bifs, status = pseudo_arclength(
        lambda x: steep_fold_map(x, count=count), np.array([0.5, 0.0, 0.25]), -1.0,
        (-1.0, 1.5), **dict(KW, tol=tol),
    )  # fmt: skip
    assert [b[0] for b in bifs] == ["fold"] and abs(bifs[0][1]) < 1e-8
    assert status == "precision-limit"
    z1, lam = xs[:, 0], xs[:, 2]
    w = np.exp(-30.0 * z1)
    g_z = (-2.0 * z1 - 30.0 * (lam - z1 * z1)) * w
    floor = EPS * (np.abs(g_z) + w) * np.maximum(np.abs(z1), np.abs(lam))
    # every point on the analytic branch to tol plus the noise it was evaluated with
    assert np.all(np.abs(lam - z1 * z1) * w <= tol + 0.3 * floor)
    # not cut short: the last point is where the floor exceeds tol (from 1.4e-16 at the
    # start), on the unstable side with a multiplier > 1e4
    assert floor[0] < 1e-3 * tol and floor[-1] > tol
    assert z1[-1] < -0.3 and mults[-1, 0].real > 1e4
    # the plain corrector needs 588 evaluations and 72 points for this branch (and ends
    # "step-too-small"): failing correctors at the floor ran all 7 iterations (191 and 23
    # points with the stop rules)
    assert len(count) < 300


@pytest.fixture(scope="module")
def branch():
    s = ssf.System.preset("asymmetric", eta=2.0)
    o = ssf.find_orbit(s, ssf.simulate(s, 20000, stop="converged"))
    return o, continue_orbit(o, "eta", (1.9, 2.1), ds=0.02, ds_max=0.05, max_points=30)


def test_orbit_branch_matches_brute_force(branch, tmp_path):
    o, br = branch
    assert br.status == "bounds" and br.values[0] == 2.0 and abs(br.values[-1] - 2.1) < 1e-9
    assert np.all(np.diff(br.values) > 0) and br.stable.all() and br.bifurcations == []
    np.testing.assert_allclose(br.points[0], o.points[0], atol=1e-12)
    # brute force at two branch values: the converged simulation's point with the smallest x1
    for i in (1, len(br.values) - 2):
        s = o.system.replace(eta=float(br.values[i]))
        r = ssf.simulate(s, 20000, stop="converged", rtol=1e-11, atol=1e-13)
        assert r.period == 1
        np.testing.assert_allclose(br.points[i], r.poincare[-1], rtol=0, atol=1e-8)
        assert abs(br.T[i] - np.diff(r.t_poincare[-2:])[0]) < 1e-6
    # the file round-trips, with h5py and with xarray
    path = br.to_hdf5(tmp_path / "branch.h5")
    import h5py

    with h5py.File(path, "r") as h5:
        assert h5.attrs["kind"] == "branch" and h5.attrs["param"] == "eta"
        np.testing.assert_array_equal(h5["values"][()], br.values)
        np.testing.assert_array_equal(h5["multipliers_real"][()], br.multipliers.real)
    xr = pytest.importorskip("xarray")
    ds = xr.open_dataset(path, engine="h5netcdf", phony_dims="sort")
    np.testing.assert_array_equal(ds["T"].values, br.T)
    ds.close()


def test_bad_input_names_the_argument(branch):
    o, _ = branch
    with pytest.raises(ValueError, match="bounds"):
        continue_orbit(o, "eta", (2.5, 3.0))
    with pytest.raises(ValueError, match="param"):
        continue_orbit(o, "n_oscillators", (1.0, 3.0))
    with pytest.raises(ValueError, match="param"):
        continue_orbit(o, "speed", (1.0, 3.0))
    with pytest.raises(ValueError, match="ds"):
        continue_orbit(o, "eta", (1.0, 3.0), ds=-0.1)
    with pytest.raises(ValueError, match="orbit"):
        continue_orbit(ssf.find_orbit(o.system, o.points[0] + [1e-3, 0, 0, 0], 1, max_iter=0), "eta", (1.0, 3.0))  # fmt: skip


def test_branch_reaches_the_issue_value_at_eta_3_30(branch):
    # From rest the period-1 orbit is not reached at eta = 3.30 (the run ends at rest); the
    # branch from eta = 2.0 gets there. Issue 10's independent shooting: multiplier -0.171.
    o, _ = branch
    br = continue_orbit(o, "eta", (2.0, 3.28), ds=0.05, ds_max=0.1, max_points=60)
    assert br.status == "bounds" and br.stable.all() and br.bifurcations == []
    o3 = ssf.find_orbit(o.system.replace(eta=3.30), br.points[-1], 1)
    assert o3.converged and o3.stable
    assert abs(o3.multipliers[0] - (-0.171)) < 1e-3


def test_orbit_branch_progress_bar_counts_its_points(branch, capsys):
    o, br = branch
    shown = continue_orbit(o, "eta", (1.9, 2.1), ds=0.02, ds_max=0.05, max_points=30,
                           progress=True)  # fmt: skip
    err = capsys.readouterr().err
    n = len(shown.values)
    assert "continue_orbit eta" in err and f"{n}/{n} [" in err
    assert f"eta={shown.values[-1]:.10g}" in err
    np.testing.assert_array_equal(shown.points, br.points)  # the same branch


def test_cli_continue_writes_the_api_branch_and_info_reads_it(branch, tmp_path, capsys):
    from stickslip_fast.bifurcation.continuation import Branch
    from stickslip_fast.cli import main

    _, br = branch
    cfg = tmp_path / "c.toml"
    cfg.write_text(
        '[system]\npreset = "asymmetric"\neta = 2.0\n'
        '[integration]\nt_end = 20000.0\nstop = "converged"\n'
        '[continue]\nparam = "eta"\nbounds = [1.9, 2.1]\nds = 0.02\nds_max = 0.05\n'
        "max_points = 30\n"
    )
    out = tmp_path / "b.h5"
    assert main(["continue", str(cfg), "-o", str(out)]) == 0
    got = Branch.from_hdf5(out)
    # the same orbit and branch as the API gives from the same simulation
    np.testing.assert_array_equal(got.values, br.values)
    np.testing.assert_array_equal(got.points, br.points)
    np.testing.assert_array_equal(got.multipliers, br.multipliers)
    assert got.period == 1 and got.status == br.status == "bounds" and got.param == "eta"
    assert got.system == br.system and got.stable.all()
    # the leading multiplier at eta = 2.0: -0.0969 by independent finite-difference shooting
    assert abs(np.abs(got.multipliers[0]).max() - 0.0969) < 5e-4
    text = capsys.readouterr().out
    assert "period 1 in eta" in text and "bifurcations: none detected" in text
    assert main(["info", str(out)]) == 0
    assert "(branch)" in capsys.readouterr().out


def test_cli_continue_errors_name_the_problem(tmp_path, capsys):
    from stickslip_fast.cli import main

    cfg = tmp_path / "c.toml"
    cfg.write_text('[system]\npreset = "asymmetric"\neta = 2.0\n')
    assert main(["continue", str(cfg), "-o", str(tmp_path / "b.h5")]) == 2
    assert "[continue]" in capsys.readouterr().err
    cfg.write_text('[continue]\nparam = "eta"\nbounds = [1.9]\n')
    assert main(["continue", str(cfg), "-o", str(tmp_path / "b.h5")]) == 2
    assert "[continue].bounds" in capsys.readouterr().err
    # from rest at eta = 4.0 the zero state slides steadily: no orbit to continue
    cfg.write_text(
        '[system]\npreset = "asymmetric"\neta = 4.0\n[integration]\nt_end = 400.0\n'
        'stop = "converged"\n[continue]\nparam = "eta"\nbounds = [3.5, 4.5]\n'
    )
    assert main(["continue", str(cfg), "-o", str(tmp_path / "b.h5")]) == 2
    err = capsys.readouterr().err
    assert "no periodic orbit" in err and "'equilibrium'" in err
    assert not (tmp_path / "b.h5").exists()
    cfg.write_text('[continue]\nparam = "eta"\nbounds = [1.9, 2.1]\nsharp_ends = "yes"\n')
    assert main(["continue", str(cfg), "-o", str(tmp_path / "b.h5")]) == 2
    assert "[continue].sharp_ends" in capsys.readouterr().err
    cfg.write_text(
        '[continue]\nparam = "eta"\nbounds = [1.9, 2.1]\nstart = "sliding"\nsharp_ends = false\n'
    )
    assert main(["continue", str(cfg), "-o", str(tmp_path / "b.h5")]) == 2
    assert "[continue].sharp_ends applies to start = 'orbit'" in capsys.readouterr().err


def fold_pd_map_twice(x):
    # the second iterate of fold_pd_map: z1 -> f(f(z1)), f(z) = z + lam - z^2; z2 -> z2 / 4.
    # Its period-2 points are z1 = 1 +- sqrt(lam - 1) (lam > 1), with multiplier
    # f'(z) f'(w) = 5 - 4 lam: stable on (1, 1.5), a period-doubling again at lam = 1.5
    z1, z2, lam = x
    w = z1 + lam - z1 * z1
    ww = w + lam - w * w
    d = (1 - 2 * w) * (1 - 2 * z1)
    A = np.diag([d, 0.25])
    G = np.array([ww - z1, -0.75 * z2])
    DG = np.array([[d - 1.0, 0.0, (1 - 2 * w) + 1.0], [0.0, -0.75, 0.0]])
    return True, G, DG, A


def test_period_doubling_branch_switching_on_the_analytic_map():
    xs, mults, bifs, _ = pseudo_arclength(
        fold_pd_map, np.array([0.5, 0.0, 0.25]), 1.0, (-1.0, 1.5), **KW
    )
    kind, lam_pd, _, x_pd = bifs[0]
    assert kind == "period-doubling"
    # the -1 eigenvector of the map's Jacobian at the located point
    _, _, _, A = fold_pd_map(x_pd)
    mu, vecs = np.linalg.eig(A)
    v = np.real(vecs[:, np.argmin(np.abs(mu + 1))])
    for delta in (1e-2, 1e-3):
        ok, x = period_doubling_start(fold_pd_map_twice, x_pd, v, delta, tol=1e-13)
        assert ok
        # on the doubled branch: (z1 - 1)^2 = lam - 1, off the period-1 branch z1^2 = lam
        assert abs(abs(x[0] - 1.0) - delta) < 1e-7
        assert abs((x[0] - 1.0) ** 2 - (x[2] - 1.0)) < 1e-12
        assert abs(x[0] ** 2 - x[2]) > 1e-3
    # continued away from the period-doubling: the whole doubled branch, its multiplier
    # 5 - 4 lam, and its own period-doubling at lam = 1.5
    xs2, mults2, bifs2, status2 = pseudo_arclength(fold_pd_map_twice, x, 1.0, (0.9, 1.6), **KW)
    np.testing.assert_allclose((xs2[:, 0] - 1.0) ** 2, xs2[:, 2] - 1.0, atol=1e-10)
    d = 5.0 - 4.0 * xs2[:, 2]
    assert np.all(np.min(np.abs(mults2 - d[:, None]), axis=1) < 1e-9)
    assert [b[0] for b in bifs2] == ["period-doubling"]
    assert abs(bifs2[0][1] - 1.5) < 1e-8


# A point of the period-2 orbit of Fig. 6 (asymmetric set, constant belt) near its lower
# end, from continue_orbit started at eta = 7.0 (data/continuation/fig06_p2.toml)
P2_ETA = 5.043198103554579
P2_POINT = [0.027234629670059556, 0.0, 0.12785148813700828, -0.0038733936156032087]


def test_switching_at_the_period_doubling_of_fig6_p2_gives_a_period_4_orbit():
    s = ssf.System.preset("asymmetric", eta=P2_ETA)
    o2 = ssf.find_orbit(s, np.array(P2_POINT), period=2)
    assert o2.converged and o2.stable
    br = continue_orbit(o2, "eta", (5.0428, 5.0433), ds=2e-5, ds_min=1e-9, ds_max=4e-5,
                        max_points=8, direction=-1)  # fmt: skip
    pds = [b for b in br.bifurcations if b.kind == "period-doubling"]
    assert len(pds) == 1 and abs(pds[0].value - 5.042952433) < 1e-8
    o4 = ssf.switch_branch(br, pds[0])
    assert o4.converged and o4.period == 4 and o4.residual <= 1e-10
    # a genuine period-4 orbit (its halves differ), born on the side where the
    # period-2 orbit is stable, and unstable: the period-doubling is subcritical
    assert np.max(np.abs(o4.points[0] - o4.points[2])) > 1e-7
    d_eta = o4.system.eta - pds[0].value
    assert 0 < d_eta < 1e-5
    assert not o4.stable and 1.0 < abs(o4.multipliers[0]) < 1.1
    # brute force: from its first point the flow returns through its four points
    r = ssf.simulate(o4.system, o4.T * 1.01, y0=o4.points[0], rtol=1e-12, atol=1e-14)
    assert r.poincare.shape[0] == 4
    np.testing.assert_allclose(r.poincare, o4.points[[1, 2, 3, 0]], atol=1e-7)
    np.testing.assert_allclose(r.t_poincare, o4.times, atol=1e-6)
    # continued upwards, the branch grows unstable and ends where its recorded return time
    # would jump (42.38 -> 31.99 within 1.5e-6 in eta, which the branch used to accept):
    # never a branch that mixes two families of fixed points of P^4
    b4 = continue_orbit(o4, "eta", (5.0428, 5.0440), ds=2e-5, ds_min=1e-9, ds_max=4e-5,
                        max_points=400, stick_events=False)  # fmt: skip
    assert np.all(np.abs(np.diff(b4.T)) <= 0.05 * b4.T[:-1])
    assert abs(b4.T[-1] - o4.T) < 1e-2 and b4.values[-1] > 5.04299
    assert b4.status == "nonsmooth" and b4.bifurcations[-1].kind == "section-grazing"
    assert np.nanmax(np.abs(b4.multipliers[-1])) > 1e5


def test_switch_branch_rejects_what_is_not_a_period_doubling(branch):
    _, br = branch
    with pytest.raises(ValueError, match="bifurcation"):
        ssf.switch_branch(br, 0)  # the branch has no bifurcations
    eq_branch = dataclasses.replace(br, period=0)
    with pytest.raises(ValueError, match="branch"):
        ssf.switch_branch(eq_branch, 0)
    fold = ssf.Bifurcation("fold", 2.0, 0, br.points[0])
    with pytest.raises(ValueError, match="period-doubling"):
        ssf.switch_branch(dataclasses.replace(br, bifurcations=[fold]), fold)


def test_a_stick_phase_appearing_along_fig6_p2_is_located(tmp_path):
    """Fig. 6's period-2 orbit has one stick phase per period at eta = 7 and two at 8
    (brute force from rest agrees); the continuation records the counts and locates the
    change to 1e-8 in eta as a "stick-phase" event."""
    for eta, count in ((7.0, 1), (8.0, 2)):
        s = ssf.System.preset("asymmetric", eta=eta)
        o = ssf.find_orbit(s, ssf.simulate(s, 20000, stop="converged"))
        assert o.period == 2 and ssf.stick_phases(s, o.points[0], o.T).size == count
        if eta == 7.0:
            start = o
    br = continue_orbit(start, "eta", (7.0, 8.0), ds=0.05, ds_max=0.1, max_points=40)
    assert br.status == "bounds" and br.stable.all()
    assert br.stick_count[0] == 1 and br.stick_count[-1] == 2
    events = [b for b in br.bifurcations if b.kind == "stick-phase"]
    assert len(events) == 1 and 7.6 < events[0].value < 7.75
    i = events[0].index
    assert br.stick_count[i] == 1 and br.stick_count[i + 1] == 2
    # the located point is past the change: its orbit has two stick phases
    s_ev = ssf.System.preset("asymmetric", eta=events[0].value)
    o_ev = ssf.find_orbit(s_ev, events[0].point, period=2)
    assert o_ev.converged and ssf.stick_phases(s_ev, o_ev.points[0], o_ev.T).size == 2
    assert events[0].label == "S"
    # schema 2 keeps the located points and the stick geometry; schema 1 files still read
    import h5py

    path = br.to_hdf5(tmp_path / "p2.h5")
    back = Branch.from_hdf5(path)
    np.testing.assert_array_equal(back.stick_count, br.stick_count)
    np.testing.assert_array_equal(back.stick_time, br.stick_time)
    np.testing.assert_array_equal(back.bifurcations[0].point, events[0].point)
    with h5py.File(path, "a") as h5:
        h5.attrs["schema_version"] = 1
        for name in ("bifurcation_point", "stick_count", "stick_time"):
            del h5[name]
    old = Branch.from_hdf5(path)
    assert old.stick_count is None
    np.testing.assert_array_equal(old.bifurcations[0].point, br.points[i])


def test_cli_continue_switches_at_the_period_doubling(tmp_path, capsys):
    from stickslip_fast.cli import main

    cfg = tmp_path / "c.toml"
    base = (
        f'[system]\npreset = "asymmetric"\neta = {P2_ETA!r}\n'
        f"[initial]\ny0 = {P2_POINT!r}\n"
        '[integration]\nt_end = 3000.0\nstop = "converged"\n'
        '[continue]\nparam = "eta"\nbounds = [5.0428, 5.0433]\ndirection = -1\n'
        "ds = 2e-5\nds_min = 1e-9\nds_max = 4e-5\nmax_points = 8\n"
    )
    cfg.write_text(base + "switch = true\n")
    out = tmp_path / "b.h5"
    assert main(["continue", str(cfg), "-o", str(out)]) == 0
    p2 = Branch.from_hdf5(out)
    pd = [b for b in p2.bifurcations if b.kind == "period-doubling"]
    assert p2.period == 2 and len(pd) == 1
    p4 = Branch.from_hdf5(tmp_path / "b.pd1.h5")
    # the doubled branch starts at the switched orbit, just above the period-doubling
    assert p4.period == 4 and 0 < p4.values[0] - pd[0].value < 1e-5
    assert not p4.stable[0] and np.all(np.diff(p4.values) > 0)
    assert "b.pd1.h5" in capsys.readouterr().out
    cfg.write_text(base + 'switch = "yes"\n')
    assert main(["continue", str(cfg), "-o", str(out)]) == 2
    assert "[continue].switch" in capsys.readouterr().err
    cfg.write_text(base.replace("direction = -1", 'start = "sliding"') + "switch = true\n")
    assert main(["continue", str(cfg), "-o", str(out)]) == 2
    assert "[continue].switch" in capsys.readouterr().err


#: A point of Fig. 6's period-1 orbit close to its upper end (continued from eta = 2.0).
P1_END_ETA = 3.323602439463245
P1_END_POINT = [0.0725923842670777, 0.0, 0.12216897433548599, -0.006665698398121293]


def test_the_sharp_upper_end_of_fig6_p1_is_a_fold_and_is_passed():
    s = ssf.System.preset("asymmetric", eta=P1_END_ETA)
    o = ssf.find_orbit(s, np.array(P1_END_POINT), period=1)
    assert o.converged and o.stable and 0.0 < o.multipliers[0].real < 0.1
    br = continue_orbit(o, "eta", (3.32, 3.33), ds=1e-5, ds_max=1e-4, max_points=45,
                        stick_events=False)  # fmt: skip
    folds = [b for b in br.bifurcations if b.kind == "fold"]
    assert len(folds) == 1 and abs(folds[0].value - 3.3236646195) < 2e-10
    # past the fold: the same orbit, unstable (a real multiplier > 1), at lower eta
    k = folds[0].index
    assert br.stable[k - 1] and not br.stable[-1]
    assert br.multipliers[-1, 0].real > 1.5 and br.values[-1] < folds[0].value - 1e-7
    assert np.all(np.abs(br.T - o.T) < 1e-3)
    # without the tighter stages the corrector stops short of the fold
    short = continue_orbit(o, "eta", (3.32, 3.33), ds=1e-5, ds_max=1e-4, max_points=45,
                           stick_events=False, sharp_ends=False)  # fmt: skip
    assert short.status == "step-too-small" and np.all(short.stable)
