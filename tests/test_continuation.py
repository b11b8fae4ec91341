"""Pseudo-arclength continuation (issue 10, section 3).

The core is checked on maps whose bifurcations are known in closed form (a fold and a
period-doubling of z -> z + lambda - z^2, a Neimark-Sacker point of z -> lambda R z); the
orbit continuation against brute-force simulation of the engine. About 10 s warm.
"""

from __future__ import annotations

import numpy as np
import pytest

import stickslip_fast as ssf
from stickslip_fast.continuation import continue_orbit, pseudo_arclength

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


def test_cli_continue_writes_the_api_branch_and_info_reads_it(branch, tmp_path, capsys):
    from stickslip_fast.cli import main
    from stickslip_fast.continuation import Branch

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
