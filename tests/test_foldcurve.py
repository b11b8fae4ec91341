"""Two-parameter continuation of folds (issue 28, item 2) on normal forms with known curves.

x -> x + a + b x - x^3 (the fixed points are the equilibria of x' = a + b x - x^3): its
fold curve is (a, b) = (-2 z^3, 3 z^2) with a cusp at a = b = 0. x -> x + a^2 + b - x^2
(written in (z, a, b)): its fold curve b = -a^2 turns back in b at a = 0 (an extremum,
no cusp). A fold of a map with a second variable checks the bordering in two dimensions.
"""

from __future__ import annotations

import numpy as np
import pytest
from turning_forms import quarter_turn

from stickslip_fast.bifurcation.arclength import pseudo_arclength
from stickslip_fast.bifurcation.foldcurve import follow_curve

KW = dict(ds=0.02, ds_min=1e-8, ds_max=0.05, max_points=400, tol=1e-12)


def cusp_map(x):
    z, w, a, b = x
    A = np.array([[1 + b - 3 * z * z, 0.0], [0.0, 0.5]])
    G = np.array([a + b * z - z**3, -0.5 * w])
    DG = np.hstack([A - np.eye(2), np.array([[1.0, z], [0.0, 0.0]])])
    return True, G, DG, A


def isola_map(x):
    z, a, b = x
    A = np.array([[1 - 2 * z]])
    return True, np.array([a * a + b - z * z]), np.array([[-2 * z, 2 * a, 1.0]]), A


def test_cusp_of_the_cubic_normal_form_is_detected():
    z0 = 1 / np.sqrt(3)  # the fold at b = 1: z = sqrt(b/3), a = -2 z^3
    x0 = np.array([z0 + 1e-3, 0.0, -2 * z0**3 + 1e-3, 1.0])
    xs, _, codim2, status, _ = follow_curve(cusp_map, x0, "fold", -1, (-1.0, 1.0), **KW)
    # every point on the analytic curve
    z, a, b = xs[:, 0], xs[:, 2], xs[:, 3]
    np.testing.assert_allclose(b, 3 * z * z, atol=1e-11)
    np.testing.assert_allclose(a, -2 * z**3, atol=1e-11)
    assert z.min() < -0.5 and status == "bounds"  # through the cusp onto the other fold
    kinds = [k for k, _, _ in codim2]
    assert kinds == ["cusp"], codim2
    np.testing.assert_allclose(codim2[0][2][[0, 2, 3]], 0.0, atol=1e-6)


def test_extremum_is_not_a_cusp():
    x0 = np.array([0.0, 0.5, -0.25 + 1e-3])
    xs, _, codim2, status, _ = follow_curve(isola_map, x0, "fold", 1, (-1.0, 1.0), **KW)
    np.testing.assert_allclose(xs[:, 2], -(xs[:, 1] ** 2), atol=1e-11)
    assert [k for k, _, _ in codim2] == ["extremum"], codim2
    np.testing.assert_allclose(codim2[0][2][1:], 0.0, atol=1e-6)


def test_fold_curve_passes_through_one_parameter_folds():
    # the fold curve, ended on the bound b (its last point has b exactly), against the fold
    # located by one-parameter continuation in a at that fixed b
    x0 = np.array([1 / np.sqrt(3), 0.0, -2 / (3 * np.sqrt(3)), 1.0])
    for b in (0.9, 0.6, 0.3):
        xs, _, _, status, _ = follow_curve(cusp_map, x0, "fold", -1, (b, 1.0), **KW)
        assert status == "bounds" and xs[-1, 3] == b

        def at_b(y, b=b):
            ok, G, DG, A = cusp_map(np.r_[y[:2], y[2], b])
            return ok, G, DG[:, :3], A

        z = np.sqrt(b / 3) + 0.3  # on the upper branch, past the fold in a
        start = np.array([z, 0.0, z**3 - b * z])
        _, _, bifs, _ = pseudo_arclength(at_b, start, -1, (-2.0, 2.0), **KW)
        fold = [x for k, _, _, x in bifs if k == "fold"][0]
        # the parameter (the one-parameter locator stops at locate_tol = 1e-9); z only to
        # ~sqrt of that at a fold
        assert abs(xs[-1, 2] - fold[2]) < 1e-8
        assert abs(xs[-1, 0] - fold[0]) < 1e-4
        np.testing.assert_allclose(xs[-1, 2], -2 * (b / 3) ** 1.5, atol=1e-12)


def test_curve_file_round_trip(tmp_path):
    import stickslip_fast as ssf

    s = ssf.System.preset("asymmetric", eta=3.3)
    c = ssf.Curve(
        system=s, param="eta", param2="k12", kind="fold", period=1,
        values=np.array([[3.3, -0.8], [3.2, -0.81]]), points=np.arange(8.0).reshape(2, 4),
        T=np.array([14.0, 14.1]), multipliers=np.array([[1.0, 1e-8j, 0.0], [1.0, 0.1, 0.0]]),
        codim2=[ssf.Codim2Point("extremum", np.array([3.0, -0.83]), 0, np.ones(4))],
        status="bounds",
    )  # fmt: skip
    back = ssf.Curve.from_hdf5(c.to_hdf5(tmp_path / "c.h5"))
    assert back.system == s and (back.param, back.param2, back.kind) == ("eta", "k12", "fold")
    for name in ("values", "points", "T", "multipliers"):
        np.testing.assert_array_equal(getattr(back, name), getattr(c, name))
    assert back.codim2[0].kind == "extremum" and back.codim2[0].index == 0
    np.testing.assert_array_equal(back.codim2[0].values, [3.0, -0.83])
    assert back.status == "bounds"
    # the file is xarray-readable (docs/file-format.md), as the branch files are
    xr = pytest.importorskip("xarray")
    with xr.open_dataset(tmp_path / "c.h5", engine="h5netcdf", phony_dims="sort") as ds:
        np.testing.assert_array_equal(ds["values"].values, c.values)
        np.testing.assert_array_equal(ds["T"].values, c.T)
        assert ds.attrs["param2"] == "k12"
    with pytest.raises(ValueError, match="not a curve file"):
        import h5py

        with h5py.File(tmp_path / "x.h5", "w") as h5:
            h5.attrs["kind"] = "branch"
        ssf.Curve.from_hdf5(tmp_path / "x.h5")


def henon(x):
    # (x, y) -> (1 - a x^2 + y, b x): period-doubling curve a = 3 (1 - b)^2 / 4, fold curve
    # a = -(1 - b)^2 / 4; the multipliers' product is -b, so the second multiplier is b on
    # the former (1:2 resonance at b = -1) and -b on the latter (1:1 resonance at b = -1)
    u, v, a, b = x
    A = np.array([[-2 * a * u, 1.0], [b, 0.0]])
    G = np.array([1 - a * u * u + v - u, b * u - v])
    return True, G, np.hstack([A - np.eye(2), [[-u * u, 0.0], [0.0, u]]]), A


def _henon_start(b, kind):
    u = 2 / (3 * (1 - b)) if kind == "period-doubling" else 2 / (1 - b)
    a = (3 if kind == "period-doubling" else -1) * (1 - b) ** 2 / 4
    return np.array([u + 1e-3, b * u, a - 1e-3, b])


def test_period_doubling_curve_and_1_2_resonance_of_the_henon_map():
    xs, mults, codim2, status, _ = follow_curve(
        henon, _henon_start(0.3, "period-doubling"), "period-doubling", -1, (-1.5, 0.9), **KW
    )
    a, b = xs[:, 2], xs[:, 3]
    assert status == "bounds" and b[-1] == -1.5
    np.testing.assert_allclose(a, 0.75 * (1 - b) ** 2, rtol=1e-11, atol=1e-12)
    np.testing.assert_allclose(xs[:, 0], 2 / (3 * (1 - b)), atol=1e-10)
    # the multipliers: -1 and b
    np.testing.assert_allclose(np.sort(mults.real, axis=1), np.c_[np.minimum(b, -1),
                               np.maximum(b, -1)], atol=1e-8)  # fmt: skip
    assert [k for k, _, _ in codim2] == ["1:2"], codim2
    np.testing.assert_allclose(codim2[0][2][2:], [3.0, -1.0], atol=1e-8)


def test_fold_curve_and_1_1_resonance_of_the_henon_map():
    xs, _, codim2, status, _ = follow_curve(henon, _henon_start(0.3, "fold"), "fold", -1,
                                            (-1.5, 0.9), **KW)  # fmt: skip
    a, b = xs[:, 2], xs[:, 3]
    assert status == "bounds"
    np.testing.assert_allclose(a, -0.25 * (1 - b) ** 2, rtol=1e-11, atol=1e-12)
    assert [k for k, _, _ in codim2] == ["1:1"], codim2
    np.testing.assert_allclose(codim2[0][2][2:], [-1.0, -1.0], atol=1e-8)


def fold_flip_map(x):
    # (u, w) -> (u + a - u^2, -(1 + b + u) w + w^3) at w = 0: fold curve a = 0 (multipliers
    # 1, -(1 + b)), period-doubling curve a = b^2 with u = -b (multipliers 1 + 2b, -1);
    # both have a fold-flip point at a = b = 0 (its 1:2 point at b = -1, where A + I = 0, is
    # degenerate: the Henon map's is tested above)
    u, w, a, b = x
    A = np.array([[1 - 2 * u, 0.0], [-w, -(1 + b + u) + 3 * w * w]])
    G = np.array([a - u * u, -(2 + b + u) * w + w**3])
    return True, G, np.hstack([A - np.eye(2), [[1.0, 0.0], [0.0, -w]]]), A


def test_fold_flip_on_fold_and_period_doubling_curves():
    xs, _, codim2, status, _ = follow_curve(fold_flip_map, np.array([1e-3, 0.0, 1e-4, 0.5]),
                                            "fold", -1, (-1.0, 1.0), **KW)  # fmt: skip
    np.testing.assert_allclose(xs[:, [0, 2]], 0.0, atol=1e-11)
    assert [k for k, _, _ in codim2] == ["fold-flip"] and status == "bounds"
    np.testing.assert_allclose(codim2[0][2][2:], 0.0, atol=1e-8)
    # the period-doubling curve from b = -0.5 (u = 0.5, a = 0.25) towards b = +0.5
    xs, _, codim2, status, _ = follow_curve(
        fold_flip_map, np.array([0.5, 0.0, 0.25 + 1e-3, -0.5]), "period-doubling", 1,
        (-1.2, 0.5), **KW)  # fmt: skip
    np.testing.assert_allclose(xs[:, 2], xs[:, 3] ** 2, atol=1e-11)
    np.testing.assert_allclose(xs[:, 0], -xs[:, 3], atol=1e-11)
    assert [k for k, _, _ in codim2] == ["fold-flip"] and status == "bounds"
    np.testing.assert_allclose(codim2[0][2][2:], 0.0, atol=1e-8)


def rotating_fold(x):
    # x -> x + R F(R^T x) with F = (a - 0.3 sin(th) - u1^2, -u2 / 2): the fold curve is
    # a = 0.3 sin(th), z = 0, and its null vector R e1 turns by phi(th), a quarter turn by
    # th = 1.5, where it stays: orthogonal to the start's borders from there on
    z, a, th = x[:2], x[2], x[3]
    phi, dphi = quarter_turn(th)
    c, s = np.cos(phi), np.sin(phi)
    R, dR = np.array([[c, -s], [s, c]]), np.array([[-s, -c], [c, -s]])
    u = R.T @ z
    F = np.array([a - 0.3 * np.sin(th) - u[0] ** 2, -0.5 * u[1]])
    DFu = np.array([[-2 * u[0], 0.0], [0.0, -0.5]])
    Gz = R @ DFu @ R.T
    Gth = dphi * (dR @ F + R @ DFu @ (dR.T @ z)) + R @ np.array([-0.3 * np.cos(th), 0.0])
    return True, R @ F, np.column_stack([Gz, R[:, 0], Gth]), np.eye(2) + Gz


def test_borders_follow_a_turning_null_vector():
    # With the start's borders the bordered matrix is singular once the null vector has
    # turned a quarter: the fixed curve crawls at th = 1.5 until max_points. Adapted
    # borders pass and end on the bound, every point on the analytic curve.
    x0 = np.array([0.0, 0.0, 1e-3, 0.0])
    kw = dict(KW, max_points=200)
    xs, _, _, status, _ = follow_curve(rotating_fold, x0, "fold", 1, (-0.1, 3.2),
                                       borders="fixed", **kw)  # fmt: skip
    assert status != "bounds" and xs[-1, 3] < 1.5 + 1e-3
    xs, _, codim2, status, _ = follow_curve(rotating_fold, x0, "fold", 1, (-0.1, 3.2), **kw)
    assert status == "bounds" and xs[-1, 3] == 3.2
    np.testing.assert_allclose(xs[:, 2], 0.3 * np.sin(xs[:, 3]), rtol=0, atol=1e-11)
    np.testing.assert_allclose(xs[:, :2], 0.0, atol=1e-11)
    assert codim2 == []  # the turn of a = 0.3 sin(th) in a at th = pi/2 is no codim-2 point
    with pytest.raises(ValueError, match="borders"):
        follow_curve(rotating_fold, x0, "fold", 1, (-0.1, 3.2), borders="free", **kw)
