"""Two-parameter curves of folds and Hopf points of equilibria (issue 28, item 2), on
normal forms with known curves and codim-2 points.

Bogdanov-Takens: x' = y, y' = b1 + b2 x + x^2 - x y: fold curve b1 = b2^2 / 4, Hopf curve
b1 = 0 (b2 < 0, omega^2 = -b2), both through the BT point b1 = b2 = 0. Bautin (generalized
Hopf), centred at (b2, 0): z' = (b1 + i) z + b2 z |z|^2 - z |z|^4: Hopf curve b1 = 0 with
first Lyapunov coefficient 2 b2 (in the normalization <q, q> = 1: z = sqrt(2) w), a
Bautin point at b2 = 0. Zero-Hopf: x' = b1 - x^2, (u + iv)' = (b2 + x + i)(u + iv): fold
curve b1 = 0 with the pair's real part b2, Hopf curve b1 = b2^2 (x = -b2, the third
eigenvalue 2 b2), both through the zero-Hopf point b1 = b2 = 0.
"""

from __future__ import annotations

import numpy as np
import pytest
from turning_forms import plane_turn

import stickslip_fast as ssf
from stickslip_fast.bifurcation.hopfcurve import (
    first_lyapunov,
    follow_equilibrium_fold,
    follow_hopf_curve,
)

KW = dict(ds=0.02, ds_min=1e-8, ds_max=0.05, max_points=400, tol=1e-12)


def bt(x):
    u, v, b1, b2 = x
    J = np.array([[0.0, 1.0], [b2 + 2 * u - v, -u]])
    f = np.array([v, b1 + b2 * u + u * u - u * v])
    return True, f, np.hstack([J, [[0.0, 0.0], [1.0, u]]]), J


def bautin(x):
    u, v, b1, b2 = x
    X, Y = u - b2, v
    R = X * X + Y * Y
    s, ds = b2 * R - R * R, 2 * (b2 - 2 * R)
    J = np.array([[b1 + s + X * ds * X, -1 + X * ds * Y], [1 + Y * ds * X, b1 + s + Y * ds * Y]])
    f = np.array([b1 * X - Y + s * X, X + b1 * Y + s * Y])
    return True, f, np.c_[J, [X, Y], np.array([X * R, Y * R]) - J[:, 0]], J


def zero_hopf(x):
    z, u, v, b1, b2 = x
    r = b2 + z
    J = np.array([[-2 * z, 0.0, 0.0], [u, r, -1.0], [v, 1.0, r]])
    f = np.array([b1 - z * z, r * u - v, u + r * v])
    return True, f, np.c_[J, [1.0, 0.0, 0.0], [0.0, u, v]], J


def _kinds(codim2):
    return [k for k, _, _ in codim2]


def test_bogdanov_takens_on_the_fold_and_hopf_curves():
    xs, ev, codim2, status, _ = follow_equilibrium_fold(
        bt, np.array([-0.5 + 1e-3, 0.0, 0.25 - 1e-3, 1.0]), -1, (-1.0, 1.0), **KW
    )
    b1, b2 = xs[:, 2], xs[:, 3]
    assert status == "bounds" and b2[-1] == -1.0
    np.testing.assert_allclose(b1, b2**2 / 4, atol=1e-11)
    np.testing.assert_allclose(xs[:, 0], -b2 / 2, atol=1e-11)
    np.testing.assert_allclose(np.sort(ev.real, axis=1), np.sort(np.c_[0 * b2, b2 / 2], axis=1),
                               atol=1e-9)  # fmt: skip
    assert _kinds(codim2) == ["bogdanov-takens"], codim2
    np.testing.assert_allclose(codim2[0][2], 0.0, atol=1e-8)
    # the Hopf curve from b2 = -1 (omega = 1) up through the BT point, as a neutral saddle
    xs, ev, codim2, status, _ = follow_hopf_curve(
        bt, np.array([1e-3, 0.0, 1.0, 1e-3, -1.0]), 1, (-1.0, 0.5), **KW
    )
    kappa, b1, b2 = xs[:, 2], xs[:, 3], xs[:, 4]
    assert status == "bounds" and b2[-1] == 0.5
    np.testing.assert_allclose(b1, 0.0, atol=1e-11)
    np.testing.assert_allclose(kappa, -b2, atol=1e-11)
    np.testing.assert_allclose(ev[b2 < 0].real, 0.0, atol=1e-9)
    assert _kinds(codim2) == ["bogdanov-takens"], codim2
    np.testing.assert_allclose(codim2[0][2][2:], 0.0, atol=1e-8)


def test_bautin_point_and_the_first_lyapunov_coefficient():
    xs, ev, codim2, status, _ = follow_hopf_curve(
        bautin, np.array([-0.5 + 1e-3, 1e-3, 1.0, 2e-3, -0.5]), 1, (-0.5, 0.5), **KW
    )
    kappa, b1, b2 = xs[:, 2], xs[:, 3], xs[:, 4]
    assert status == "bounds"
    np.testing.assert_allclose(b1, 0.0, atol=1e-11)
    np.testing.assert_allclose(kappa, 1.0, atol=1e-11)
    np.testing.assert_allclose(xs[:, 0], b2, atol=1e-11)
    assert _kinds(codim2) == ["bautin"], codim2
    assert abs(codim2[0][2][-1]) < 1e-7
    for x in xs[::7]:
        ok, _, _, J = bautin(np.r_[x[:2], x[3:]])
        l1 = first_lyapunov(lambda y, x=x: bautin(np.r_[y, x[3:]])[3], x[:2], J, 1.0)
        assert abs(l1 - 2 * x[-1]) < 1e-6, (x, l1)


def test_zero_hopf_on_the_fold_and_hopf_curves():
    xs, ev, codim2, status, _ = follow_equilibrium_fold(
        zero_hopf, np.array([1e-3, 0.0, 0.0, 1e-3, -0.5]), 1, (-0.5, 0.5), **KW
    )
    np.testing.assert_allclose(xs[:, [0, 1, 2, 3]], 0.0, atol=1e-11)
    assert _kinds(codim2) == ["zero-hopf"] and status == "bounds", codim2
    np.testing.assert_allclose(codim2[0][2], 0.0, atol=1e-8)
    xs, ev, codim2, status, _ = follow_hopf_curve(
        zero_hopf, np.array([0.5 + 1e-3, 0.0, 0.0, 1.0, 0.25, -0.5]), 1, (-0.5, 0.5), **KW
    )
    z, kappa, b1, b2 = xs[:, 0], xs[:, 3], xs[:, 4], xs[:, 5]
    assert status == "bounds" and b2[-1] == 0.5
    np.testing.assert_allclose(b1, b2**2, atol=1e-11)
    np.testing.assert_allclose(z, -b2, atol=1e-11)
    np.testing.assert_allclose(kappa, 1.0, atol=1e-11)
    assert _kinds(codim2) == ["zero-hopf"], codim2
    np.testing.assert_allclose(codim2[0][2][[0, 4, 5]], 0.0, atol=1e-8)


# ---------------------------------------------------------------- the model
SYSTEM = ssf.System.preset("asymmetric", eta=2.0, drive="dc-motor")


@pytest.fixture(scope="module")
def dc_branch():
    e = ssf.find_equilibrium(SYSTEM, "sliding")
    return ssf.continue_equilibrium(e, "beta", (0.0005, 0.05), ds=0.001, ds_max=0.005,
                                    max_points=400)  # fmt: skip


def _one_parameter(kind, eta):
    """The Hopf point or upper fold in beta at this eta, by one-parameter continuation."""
    s = SYSTEM.replace(eta=float(eta), beta=0.0105)
    br = ssf.continue_equilibrium(ssf.find_equilibrium(s, "sliding"), "beta", (0.0104, 0.0115),
                                  ds=2e-5, ds_max=5e-5, max_points=80)  # fmt: skip
    return [b for b in br.bifurcations if b.kind == kind][0]


@pytest.mark.parametrize("kind", ["hopf", "fold"])
def test_dc_motor_curves_pass_through_one_parameter_points(dc_branch, kind):
    # the DC-motor drive's sliding equilibrium: its Hopf point and upper fold in beta
    # (tests/test_equilibrium_continuation.py) followed in eta
    bif = [b for b in dc_branch.bifurcations if b.kind == kind][0]
    curve = ssf.continue_bifurcation(dc_branch, bif, "eta", (1.7, 2.6), ds=0.01, ds_max=0.05)
    assert curve.status == "bounds" and curve.period == 0 and curve.kind == kind
    assert curve.values[-1, 1] == 2.6 and curve.codim2 == []
    np.testing.assert_allclose(curve.values[0], [bif.value, 2.0], atol=1e-9)
    if kind == "hopf":  # a pair on the imaginary axis (to ~1e-12 of the Jacobian's
        # largest eigenvalue, ~4e3 here), omega = 2 pi / T
        re = curve.multipliers.real[np.abs(curve.multipliers.imag) > 0.5]
        np.testing.assert_allclose(re, 0.0, atol=3e-8)
        assert np.all(np.abs(curve.T - 2 * np.pi) < 1e-3)
    else:
        assert np.all(np.isnan(curve.T))
        assert np.all(np.min(np.abs(curve.multipliers), axis=1) < 1e-6)
    for j in (len(curve.values) // 3, 2 * len(curve.values) // 3, -1):
        beta, eta = curve.values[j]
        assert abs(_one_parameter(kind, eta).value - beta) < 1e-8, (eta, beta)


def test_cli_follows_the_equilibrium_branch_s_hopf_point_and_folds(dc_branch, tmp_path, capsys):
    from stickslip_fast.cli import main

    cfg = tmp_path / "e.toml"
    cfg.write_text(
        '[system]\npreset = "asymmetric"\ndrive = "dc-motor"\neta = 2.0\n'
        '[continue]\nparam = "beta"\nbounds = [0.0005, 0.05]\nstart = "sliding"\n'
        'ds = 0.001\nds_max = 0.005\nmax_points = 400\nparam2 = "eta"\nbounds2 = [1.9, 2.1]\n'
    )
    out = tmp_path / "e.h5"
    assert main(["continue", str(cfg), "-o", str(out)]) == 0
    printed = capsys.readouterr().out
    curves = [ssf.Curve.from_hdf5(tmp_path / f"e.curve{k}.h5") for k in (1, 2, 3)]
    assert [c.kind for c in curves] == ["hopf", "fold", "fold"] and "hopf curve" in printed
    ref = ssf.continue_bifurcation(dc_branch, dc_branch.bifurcations[0], "eta", (1.9, 2.1),
                                   tol=1e-10)  # fmt: skip
    np.testing.assert_allclose(curves[0].values, ref.values, rtol=0, atol=1e-12)
    for c in curves[:2]:
        assert c.period == 0 and c.param2 == "eta" and c.status == "bounds"
        assert c.values[-1, 1] == 2.1
    # the lower fold lies inside the friction law's stick band (belt speed 6.8e-6, the
    # Jacobian's eigenvalues from -4.8e3 to -3.6e-5): Newton on the augmented system does
    # not converge there, and the curve file says so (docs/orbits.md)
    assert curves[2].status in ("start-failed", "bounds")


def test_bad_input_names_the_argument(dc_branch):
    hopf = dc_branch.bifurcations[0]
    pd = ssf.Bifurcation("period-doubling", hopf.value, hopf.index, hopf.point)
    with pytest.raises(ValueError, match="equilibrium branch"):
        ssf.continue_bifurcation(dc_branch, pd, "eta", (1.9, 2.1))
    with pytest.raises(ValueError, match="param2"):
        ssf.continue_bifurcation(dc_branch, hopf, "beta", (0.0, 0.1))
    with pytest.raises(ValueError, match="bounds2"):
        ssf.continue_bifurcation(dc_branch, hopf, "eta", (2.5, 3.0))


def test_first_lyapunov_coefficient_of_the_dc_motor_hopf_point(dc_branch):
    # the engine's Jacobian with the default step (0.01 eps) against the independent
    # SciPy/NumPy model's Jacobian (tests/reference) with a ten times smaller step: l1 > 0,
    # a subcritical Hopf point (an unstable cycle on the stable side)
    import sys
    from pathlib import Path

    from stickslip_fast.bifurcation.eqcurve import equilibrium_evaluator

    sys.path.insert(0, str(Path(__file__).parent / "reference"))
    import scipy_model

    hopf = dc_branch.bifurcations[0]
    s = SYSTEM.replace(beta=hopf.value)
    base = equilibrium_evaluator(s, "beta", "eta")
    lam = np.array([hopf.value, 2.0])
    J = base(np.r_[hopf.point, lam])[3]
    omega = np.abs(np.linalg.eigvals(J).imag).max()
    l1 = first_lyapunov(lambda y: base(np.r_[y, lam])[3], hopf.point, J, omega, 0.01 * s.eps)
    p = {**s.to_dict(), "n_oscillators": 1}
    ref = first_lyapunov(lambda y: scipy_model.jac(0.0, y, p), hopf.point,
                         scipy_model.jac(0.0, hopf.point, p), omega, 1e-3 * s.eps)  # fmt: skip
    assert l1 > 0 and abs(l1 - ref) < 1e-4 * abs(ref), (l1, ref)


def turning_hopf(x):
    # y' = Q g(Q^T y): g the Hopf normal form (mu + i) w - w |w|^2 in (u1, u2) and -u / 2
    # in (u3, u4), mu = a - 0.3 sin(th): the Hopf curve a = 0.3 sin(th) with omega = 1.
    # Q turns the (u1, u2) plane into (u3, u4) by phi(th), a quarter turn by th = 1.5,
    # where the kernel of J^2 + I is orthogonal to the start's borders
    y, a, th = x[:4], x[4], x[5]
    Q, dQ = plane_turn(th)
    u = Q.T @ y
    mu, r2 = a - 0.3 * np.sin(th), u[0] ** 2 + u[1] ** 2
    g = np.array([mu * u[0] - u[1] - u[0] * r2, u[0] + mu * u[1] - u[1] * r2,
                  -0.5 * u[2], -0.5 * u[3]])  # fmt: skip
    Dg = np.diag([0.0, 0.0, -0.5, -0.5])
    Dg[:2, :2] = [[mu - r2 - 2 * u[0] ** 2, -1 - 2 * u[0] * u[1]],
                  [1 - 2 * u[0] * u[1], mu - r2 - 2 * u[1] ** 2]]  # fmt: skip
    J = Q @ Dg @ Q.T
    f_a = Q @ np.array([u[0], u[1], 0.0, 0.0])
    f_th = dQ @ g + Q @ Dg @ (dQ.T @ y) - 0.3 * np.cos(th) * f_a
    return True, Q @ g, np.column_stack([J, f_a, f_th]), J


def test_hopf_borders_follow_a_turning_kernel():
    # Fixed borders stop short of th = 1.5; adapted borders (new borders, entries and
    # scales where the kernel has turned more than 60 degrees) end on the bound, on the
    # curve a = 0.3 sin(th) with kappa = omega^2 = 1; l1 = -2 < 0 all along: no Bautin point
    x0 = np.array([0.0, 0.0, 0.0, 0.0, 1.0, 1e-3, 0.0])
    kw = dict(KW, max_points=200)
    xs, _, _, status, _ = follow_hopf_curve(turning_hopf, x0, 1, (-0.1, 3.2), borders="fixed",
                                            **kw)  # fmt: skip
    assert status != "bounds" and xs[-1, 6] < 1.5
    xs, _, codim2, status, _ = follow_hopf_curve(turning_hopf, x0, 1, (-0.1, 3.2), **kw)
    assert status == "bounds" and xs[-1, 6] == 3.2
    np.testing.assert_allclose(xs[:, 5], 0.3 * np.sin(xs[:, 6]), rtol=0, atol=1e-11)
    np.testing.assert_allclose(xs[:, 4], 1.0, rtol=0, atol=1e-11)
    np.testing.assert_allclose(xs[:, :4], 0.0, atol=1e-11)
    assert codim2 == []
    with pytest.raises(ValueError, match="borders"):
        follow_hopf_curve(turning_hopf, x0, 1, (-0.1, 3.2), borders="free", **kw)
