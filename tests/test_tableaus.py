"""Numerical checks of the coefficient tables in ``stickslip_fast.core.tableaus``.

Each scheme is exercised through a tiny pure-NumPy reference stepper written
here, directly from the formulas in the module docstring, so these tests also
pin down the documented step / interpolation formulas.
"""

from __future__ import annotations

import sys
from collections.abc import Callable
from pathlib import Path

import numpy as np
import pytest

# Namespace-package import from the repository root (no __init__.py needed).
sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from stickslip_fast.core.tableaus import (  # noqa: E402
    DOPRI5,
    RODAS4P,
    RODAS4P2,
    RODAS5P,
    ExplicitRKTableau,
    RosenbrockTableau,
)

Array = np.ndarray
RHS = Callable[[Array], Array]

# ---------------------------------------------------------------------------
# Reference steppers (autonomous y' = f(y))
# ---------------------------------------------------------------------------


def erk_step(f: RHS, y0: Array, h: float, tab: ExplicitRKTableau) -> tuple[Array, Array, Array]:
    """One explicit RK step; returns (y1, err, k) with k of shape (s, n)."""
    s = tab.n_stages
    k = np.zeros((s, y0.size))
    for i in range(s):
        k[i] = f(y0 + h * (tab.A[i, :i] @ k[:i]))
    y1 = y0 + h * (tab.b @ k)
    err = h * (tab.b_err @ k)
    return y1, err, k


def erk_dense(y0: Array, h: float, k: Array, tab: ExplicitRKTableau, theta: float) -> Array:
    """Continuous extension y0 + h * sum_i k_i sum_m P[i, m] theta**(m+1)."""
    powers = theta ** np.arange(1, tab.dense.shape[1] + 1)
    return y0 + h * ((tab.dense @ powers) @ k)


def ros_step(
    f: RHS, jac: Callable[[Array], Array], y0: Array, h: float, tab: RosenbrockTableau
) -> tuple[Array, Array, Array]:
    """One Rosenbrock step in transformed form; returns (y1, err, k)."""
    s = tab.n_stages
    n = y0.size
    W = np.eye(n) / (h * tab.gamma) - jac(y0)
    k = np.zeros((s, n))
    u = y0
    for i in range(s):
        u = y0 + tab.a[i, :i] @ k[:i]
        k[i] = np.linalg.solve(W, f(u) + (tab.C[i, :i] @ k[:i]) / h)
    y1 = u + k[-1]
    return y1, k[-1].copy(), k


def ros_step_nonautonomous(
    f: Callable[[float, Array], Array],
    jac_y: Callable[[float, Array], Array],
    f_t: Callable[[float, Array], Array],
    t0: float,
    y0: Array,
    h: float,
    tab: RosenbrockTableau,
) -> Array:
    """Rosenbrock step for y' = f(t, y) using the c (times) and d (df/dt) terms."""
    s = tab.n_stages
    n = y0.size
    W = np.eye(n) / (h * tab.gamma) - jac_y(t0, y0)
    dfdt = f_t(t0, y0)
    k = np.zeros((s, n))
    u = y0
    for i in range(s):
        u = y0 + tab.a[i, :i] @ k[:i]
        rhs = f(t0 + tab.c[i] * h, u) + (tab.C[i, :i] @ k[:i]) / h + h * tab.d[i] * dfdt
        k[i] = np.linalg.solve(W, rhs)
    return u + k[-1]


def ros_dense(y0: Array, y1: Array, k: Array, tab: RosenbrockTableau, theta: float) -> Array:
    """(1-th) y0 + th (y1 + (1-th)(h0 + th (h1 + th h2))), h_r = H[r] @ k."""
    hr = tab.H @ k
    acc = hr[-1]
    for r in range(hr.shape[0] - 2, -1, -1):
        acc = hr[r] + theta * acc
    return (1.0 - theta) * y0 + theta * (y1 + (1.0 - theta) * acc)


def ros_stability(z: Array, tab: RosenbrockTableau) -> Array:
    """Stability function R(z): one step of y' = lam*y, y0 = 1, h = 1, z = lam."""
    z = np.asarray(z, dtype=complex)
    w = 1.0 / tab.gamma - z
    k = np.zeros((tab.n_stages,) + z.shape, dtype=complex)
    u = np.ones_like(z)
    for i in range(tab.n_stages):
        u = 1.0 + np.tensordot(tab.a[i, :i], k[:i], axes=1)
        k[i] = (z * u + np.tensordot(tab.C[i, :i], k[:i], axes=1)) / w
    return u + k[-1]


def assert_a_stable(tab: RosenbrockTableau) -> None:
    """|R(z)| <= 1 on the imaginary axis and on a sample of the open left half plane."""
    w = np.concatenate([np.linspace(0.0, 1e4, 20001), np.logspace(-3, 4, 2001)])
    assert np.max(np.abs(ros_stability(1j * w, tab))) <= 1.0 + 1e-12
    r = np.logspace(-3, 8, 221)
    phi = np.linspace(np.pi / 2, 3 * np.pi / 2, 181)
    z = (r[:, None] * np.exp(1j * phi[None, :])).ravel()
    z = z[z.real < 0]
    assert np.max(np.abs(ros_stability(z, tab))) <= 1.0 + 1e-12


def fitted_order(hs: Array, errs: Array | list[float]) -> float:
    """Least-squares slope of log(err) against log(h)."""
    return float(np.polyfit(np.log(hs), np.log(np.asarray(errs)), 1)[0])


def observed_orders(hs: Array, errs: Array) -> Array:
    """Successive slopes log(e_j / e_{j+1}) / log(h_j / h_{j+1})."""
    errs = np.asarray(errs)
    return np.log(errs[:-1] / errs[1:]) / np.log(hs[:-1] / hs[1:])


# ---------------------------------------------------------------------------
# Test problems with exact solutions
# ---------------------------------------------------------------------------
# Hopf normal form: x' = -y + x(1-r^2), y' = x + y(1-r^2).  Nonlinear, smooth,
# exact solution r(t) = 1/sqrt(1 + (1/r0^2 - 1) e^{-2t}), phase = phi0 + t.

R0, PHI0 = 0.5, 0.3


def hopf_f(y: Array) -> Array:
    q = 1.0 - y[0] ** 2 - y[1] ** 2
    return np.array([-y[1] + y[0] * q, y[0] + y[1] * q])


def hopf_jac(y: Array) -> Array:
    x, v = y
    q = 1.0 - x * x - v * v
    return np.array([[q - 2 * x * x, -1.0 - 2 * x * v], [1.0 - 2 * x * v, q - 2 * v * v]])


def hopf_exact(t: float) -> Array:
    r = 1.0 / np.sqrt(1.0 + (1.0 / R0**2 - 1.0) * np.exp(-2.0 * t))
    return np.array([r * np.cos(PHI0 + t), r * np.sin(PHI0 + t)])


# Harmonic oscillator seen through the nonlinear map z = (y1 + A y2^2, y2):
# conservative, no special error structure, exact solution known.
OSC_A = 0.3


def osc_f(z: Array) -> Array:
    y1 = z[0] - OSC_A * z[1] ** 2
    return np.array([z[1] - 2.0 * OSC_A * z[1] * y1, -y1])


def osc_jac(z: Array) -> Array:
    y1 = z[0] - OSC_A * z[1] ** 2
    return np.array(
        [
            [-2.0 * OSC_A * z[1], 1.0 - 2.0 * OSC_A * y1 + 4.0 * OSC_A**2 * z[1] ** 2],
            [-1.0, 2.0 * OSC_A * z[1]],
        ]
    )


def osc_exact(t: float) -> Array:
    y1 = np.cos(t) + 0.5 * np.sin(t)
    y2 = -np.sin(t) + 0.5 * np.cos(t)
    return np.array([y1 + OSC_A * y2**2, y2])


# Kaps problem (nonlinear, stiffness mu): exact y = (exp(-2t), exp(-t)).
KAPS_MU = 1.0e4


def kaps_f(y: Array) -> Array:
    return np.array([-(KAPS_MU + 2.0) * y[0] + KAPS_MU * y[1] ** 2, y[0] - y[1] - y[1] ** 2])


def kaps_jac(y: Array) -> Array:
    return np.array([[-(KAPS_MU + 2.0), 2.0 * KAPS_MU * y[1]], [1.0, -1.0 - 2.0 * y[1]]])


def kaps_exact(t: float) -> Array:
    return np.array([np.exp(-2.0 * t), np.exp(-t)])


# Prothero-Robinson y' = lam (y - g(t)) + g'(t), g = sin, exact y = sin(t);
# autonomous form with state (y, t).
PR_LAM = -50.0


def pr_f_t(t: float, y: Array) -> Array:
    return np.array([PR_LAM * (y[0] - np.sin(t)) + np.cos(t)])


def pr_jac_y(t: float, y: Array) -> Array:
    return np.array([[PR_LAM]])


def pr_dfdt(t: float, y: Array) -> Array:
    return np.array([-PR_LAM * np.cos(t) - np.sin(t)])


def pr_aut_f(z: Array) -> Array:
    return np.array([pr_f_t(z[1], z[:1])[0], 1.0])


def pr_aut_jac(z: Array) -> Array:
    return np.array([[PR_LAM, pr_dfdt(z[1], z[:1])[0]], [0.0, 0.0]])


def integrate(step: Callable[[Array, float], Array], y0: Array, T: float, n: int) -> Array:
    h = T / n
    y = y0.copy()
    for _ in range(n):
        y = step(y, h)
    return y


# ---------------------------------------------------------------------------
# DOPRI5
# ---------------------------------------------------------------------------


def test_dopri5_structure() -> None:
    tab = DOPRI5
    s = tab.n_stages
    assert s == 7
    assert tab.A.shape == (7, 7) and tab.dense.shape == (7, 4)
    for arr in (tab.c, tab.A, tab.b, tab.b_err, tab.dense):
        assert arr.dtype == np.float64
        assert not arr.flags.writeable
    assert np.all(np.triu(tab.A) == 0.0)
    # FSAL: last row of A equals b, last weight zero, c[-1] == 1.
    np.testing.assert_array_equal(tab.A[-1], tab.b)
    assert tab.b[-1] == 0.0 and tab.c[-1] == 1.0
    # Row sums of A equal c.
    np.testing.assert_allclose(tab.A.sum(axis=1), tab.c, rtol=0, atol=1e-15)
    # Consistency of both solutions; b_hat = b - b_err.
    assert abs(tab.b.sum() - 1.0) < 1e-15
    assert abs(tab.b_err.sum()) < 1e-15
    # Dense output reproduces y1 at theta = 1 and starts with slope k_0.
    np.testing.assert_allclose(tab.dense.sum(axis=1), tab.b, rtol=0, atol=1e-14)
    np.testing.assert_array_equal(tab.dense[:, 0], np.eye(7)[0])


def test_dopri5_classical_order_conditions() -> None:
    """Quadrature conditions sum b c^{q-1} = 1/q (q <= 5; q <= 4 for b_hat)."""
    tab = DOPRI5
    b_hat = tab.b - tab.b_err
    for q in range(1, 6):
        assert abs(tab.b @ tab.c ** (q - 1) - 1.0 / q) < 1e-14
    for q in range(1, 5):
        assert abs(b_hat @ tab.c ** (q - 1) - 1.0 / q) < 1e-14
    assert abs(b_hat @ tab.c**5 - 1.0 / 6) > 1e-6  # and not more (it is order 4)


def test_dopri5_global_order() -> None:
    T = 5.0
    ns = np.array([40, 80, 160, 320])
    errs = [
        np.linalg.norm(
            integrate(lambda y, h: erk_step(osc_f, y, h, DOPRI5)[0], osc_exact(0.0), T, n)
            - osc_exact(T)
        )
        for n in ns
    ]
    p = fitted_order(T / ns[1:], errs[1:])
    assert abs(p - 5.0) < 0.3, (p, observed_orders(T / ns, errs))
    assert errs[-1] < 1e-10


def _dopri5_local(hs: Array) -> tuple[list[float], list[float], list[float], list[float]]:
    t0 = 0.4
    y0 = hopf_exact(t0)
    est, true_hat, d3, d7 = [], [], [], []
    for h in hs:
        y1, err, k = erk_step(hopf_f, y0, h, DOPRI5)
        y1_hat = y1 - err
        est.append(np.linalg.norm(err))
        true_hat.append(np.linalg.norm(y1_hat - hopf_exact(t0 + h)))
        d3.append(np.linalg.norm(erk_dense(y0, h, k, DOPRI5, 0.3) - hopf_exact(t0 + 0.3 * h)))
        d7.append(np.linalg.norm(erk_dense(y0, h, k, DOPRI5, 0.7) - hopf_exact(t0 + 0.7 * h)))
    return est, true_hat, d3, d7


def test_dopri5_embedded_error_estimate_order() -> None:
    hs = 0.2 / 2.0 ** np.arange(4)
    est, true_hat, _, _ = _dopri5_local(hs)
    p_est = observed_orders(hs, est)
    p_true = observed_orders(hs, true_hat)
    # Local error of the 4th-order solution ~ h^5, and the estimate tracks it.
    assert abs(p_est[-1] - 5.0) < 0.3, p_est
    assert abs(p_true[-1] - 5.0) < 0.3, p_true
    assert abs(est[-1] / true_hat[-1] - 1.0) < 0.05


def test_dopri5_dense_output_order() -> None:
    hs = 0.2 / 2.0 ** np.arange(4)
    _, _, d3, d7 = _dopri5_local(hs)
    for errs in (d3, d7):
        p = observed_orders(hs, errs)
        assert abs(p[-1] - 5.0) < 0.3, p  # local error O(h^5): order-4 extension
    # The endpoints are reproduced to round-off.
    y0 = hopf_exact(0.0)
    y1, _, k = erk_step(hopf_f, y0, 0.1, DOPRI5)
    np.testing.assert_allclose(erk_dense(y0, 0.1, k, DOPRI5, 1.0), y1, rtol=0, atol=1e-15)
    np.testing.assert_array_equal(erk_dense(y0, 0.1, k, DOPRI5, 0.0), y0)


# ---------------------------------------------------------------------------
# Rodas5P
# ---------------------------------------------------------------------------


def test_rodas5p_structure() -> None:
    tab = RODAS5P
    s = tab.n_stages
    assert s == 8
    assert tab.a.shape == (s, s) and tab.C.shape == (s, s)
    assert tab.c.shape == (s,) and tab.d.shape == (s,)
    assert tab.H.shape == (3, s)
    assert (tab.order, tab.embedded_order, tab.dense_order) == (5, 4, 4)
    for arr in (tab.a, tab.C, tab.c, tab.d, tab.H):
        assert arr.dtype == np.float64
        assert not arr.flags.writeable
    assert np.all(np.triu(tab.a) == 0.0) and np.all(np.triu(tab.C) == 0.0)
    # Stiffly accurate structure: last two stage arguments chain by +k.
    e = np.eye(s)
    np.testing.assert_array_equal(tab.a[6], tab.a[5] + e[5])
    np.testing.assert_array_equal(tab.a[7], tab.a[6] + e[6])


@pytest.mark.parametrize(
    "tab", [RODAS5P, RODAS4P, RODAS4P2], ids=["rodas5p", "rodas4p", "rodas4p2"]
)
def test_rosenbrock_c_and_d_are_consistent(tab: RosenbrockTableau) -> None:
    """c = rowsum(alpha), d = rowsum(Gamma) with Gamma = inv(I/gamma - C)."""
    gam = np.linalg.inv(np.eye(tab.n_stages) / tab.gamma - tab.C)
    alpha = tab.a @ gam
    np.testing.assert_allclose(alpha.sum(axis=1), tab.c, rtol=0, atol=1e-13)
    np.testing.assert_allclose(gam.sum(axis=1), tab.d, rtol=0, atol=1e-13)
    np.testing.assert_allclose(np.diag(gam), tab.gamma, rtol=1e-14)
    assert np.abs(np.triu(alpha)).max() < 1e-14


@pytest.mark.parametrize(
    ("tab", "ns"),
    [(RODAS5P, [20, 40, 80, 160]), (RODAS4P, [40, 80, 160, 320]), (RODAS4P2, [40, 80, 160, 320])],
    ids=["rodas5p", "rodas4p", "rodas4p2"],
)
@pytest.mark.parametrize(
    ("f", "jac", "exact", "T"),
    [(osc_f, osc_jac, osc_exact, 5.0), (hopf_f, hopf_jac, hopf_exact, 2.0)],
    ids=["nonlinear-oscillator", "hopf"],
)
def test_rosenbrock_global_order(
    tab: RosenbrockTableau,
    ns: list[int],
    f: RHS,
    jac: Callable[[Array], Array],
    exact: Callable[[float], Array],
    T: float,
) -> None:
    ns = np.array(ns)
    errs = [
        np.linalg.norm(
            integrate(lambda y, h: ros_step(f, jac, y, h, tab)[0], exact(0.0), T, n) - exact(T)
        )
        for n in ns
    ]
    p = fitted_order(T / ns[1:], errs[1:])
    assert abs(p - tab.order) < 0.3, (p, observed_orders(T / ns, errs))


@pytest.mark.parametrize(
    ("tab", "ns"),
    [(RODAS5P, [10, 20, 40, 80]), (RODAS4P, [20, 40, 80, 160]), (RODAS4P2, [20, 40, 80, 160])],
    ids=["rodas5p", "rodas4p", "rodas4p2"],
)
def test_rosenbrock_prothero_robinson_autonomous_form(
    tab: RosenbrockTableau, ns: list[int]
) -> None:
    """Mildly stiff (h*lam from -5 to -0.6), nonlinear in the state (y, t): no order reduction."""
    T = 1.0
    ns = np.array(ns)
    z0 = np.array([0.0, 0.0])  # y(0) = sin(0), t(0) = 0
    errs = [
        abs(
            integrate(lambda z, h: ros_step(pr_aut_f, pr_aut_jac, z, h, tab)[0], z0, T, n)[0]
            - np.sin(T)
        )
        for n in ns
    ]
    p = fitted_order(T / ns[1:], errs[1:])
    assert abs(p - tab.order) < 0.3, (p, observed_orders(T / ns, errs))


def test_rodas5p_kaps_very_stiff_accuracy() -> None:
    """Kaps, mu = 1e4: stable and accurate with h*mu up to 1e3 (no order claim)."""
    errs = [
        np.linalg.norm(
            integrate(
                lambda y, h: ros_step(kaps_f, kaps_jac, y, h, RODAS5P)[0], kaps_exact(0.0), 1.0, n
            )
            - kaps_exact(1.0)
        )
        for n in (10, 40)
    ]
    assert errs[0] < 1e-7 and errs[1] < 5e-9, errs


def test_rodas5p_nonautonomous_c_d_match_augmented_form() -> None:
    """The c/d time terms reproduce the (t, y)-augmented autonomous step."""
    t0, h = 0.3, 0.05
    y0 = np.array([0.2])
    y_na = ros_step_nonautonomous(pr_f_t, pr_jac_y, pr_dfdt, t0, y0, h, RODAS5P)
    z1, _, _ = ros_step(pr_aut_f, pr_aut_jac, np.array([y0[0], t0]), h, RODAS5P)
    np.testing.assert_allclose(y_na[0], z1[0], rtol=1e-13, atol=1e-15)
    assert abs(z1[1] - (t0 + h)) < 1e-15


def test_rodas5p_stability_function() -> None:
    tab = RODAS5P
    # L-stability: R(-inf) = 0 (numerically |R(z)| ~ 12.5/|z|).
    assert abs(ros_stability(np.array([-1e8]), tab)[0]) < 1e-6
    assert abs(ros_stability(np.array([-1e12]), tab)[0]) < 1e-10
    # Consistency near 0: R(z) = e^z + O(z^6).
    zs = np.array([1e-2, -1e-2, 1e-2j])
    assert np.max(np.abs(ros_stability(zs, tab) - np.exp(zs))) < 1e-12
    assert_a_stable(tab)


def test_rodas5p_error_estimate_is_last_stage() -> None:
    """err = k_s is the difference to the 4th-order embedded solution, O(h^5)."""
    t0 = 0.4
    y0 = hopf_exact(t0)
    hs = 0.2 / 2.0 ** np.arange(4)
    est, true_emb = [], []
    for h in hs:
        y1, err, _ = ros_step(hopf_f, hopf_jac, y0, h, RODAS5P)
        est.append(np.linalg.norm(err))
        true_emb.append(np.linalg.norm((y1 - err) - hopf_exact(t0 + h)))
    for errs in (est, true_emb):
        p = observed_orders(hs, errs)
        assert abs(p[-1] - 5.0) < 0.3, p


def test_rodas5p_dense_output() -> None:
    t0 = 0.4
    y0 = hopf_exact(t0)
    y1, _, k = ros_step(hopf_f, hopf_jac, y0, 0.1, RODAS5P)
    np.testing.assert_array_equal(ros_dense(y0, y1, k, RODAS5P, 1.0), y1)
    np.testing.assert_array_equal(ros_dense(y0, y1, k, RODAS5P, 0.0), y0)

    hs = 0.2 / 2.0 ** np.arange(4)
    errs = []
    for h in hs:
        y1, _, k = ros_step(hopf_f, hopf_jac, y0, h, RODAS5P)
        errs.append(np.linalg.norm(ros_dense(y0, y1, k, RODAS5P, 0.5) - hopf_exact(t0 + 0.5 * h)))
    p = observed_orders(hs, errs)
    # Dense output of order 4: local error O(h^5).
    assert p[-1] >= 4.0 + 0.5, p


# ---------------------------------------------------------------------------
# Rodas4P and Rodas4P2: 6 stages, orders 4 (solution), 3 (embedded), 3 (dense)
# ---------------------------------------------------------------------------

RODAS4 = pytest.mark.parametrize("tab", [RODAS4P, RODAS4P2], ids=["rodas4p", "rodas4p2"])


@RODAS4
def test_rodas4_structure(tab: RosenbrockTableau) -> None:
    s = tab.n_stages
    assert s == 6
    assert tab.a.shape == (s, s) and tab.C.shape == (s, s) and tab.H.shape == (2, s)
    assert (tab.order, tab.embedded_order, tab.dense_order) == (4, 3, 3)
    assert tab.gamma == 0.25
    for arr in (tab.a, tab.C, tab.c, tab.d, tab.H):
        assert arr.dtype == np.float64 and not arr.flags.writeable
    assert np.all(np.triu(tab.a) == 0.0) and np.all(np.triu(tab.C) == 0.0)
    np.testing.assert_array_equal(tab.a[5], tab.a[4] + np.eye(s)[4])  # stiffly accurate


@RODAS4
def test_rodas4_error_estimate_and_dense_output(tab: RosenbrockTableau) -> None:
    """err = k_5 is O(h^4) (embedded order 3); the dense output is of order 3, exact at the ends."""
    t0 = 0.4
    y0 = hopf_exact(t0)
    y1, _, k = ros_step(hopf_f, hopf_jac, y0, 0.1, tab)
    np.testing.assert_array_equal(ros_dense(y0, y1, k, tab, 1.0), y1)
    np.testing.assert_array_equal(ros_dense(y0, y1, k, tab, 0.0), y0)
    hs = 0.2 / 2.0 ** np.arange(5)
    est, dense = [], []
    for h in hs:
        y1, err, k = ros_step(hopf_f, hopf_jac, y0, h, tab)
        est.append(np.linalg.norm(err))
        dense.append(np.linalg.norm(ros_dense(y0, y1, k, tab, 0.5) - hopf_exact(t0 + 0.5 * h)))
    assert abs(observed_orders(hs, est)[-1] - 4.0) < 0.3
    assert abs(observed_orders(hs, dense)[-1] - 4.0) < 0.3


@RODAS4
def test_rodas4_stability_function(tab: RosenbrockTableau) -> None:
    assert abs(ros_stability(np.array([-1e12]), tab)[0]) < 1e-10  # L-stable
    zs = np.array([1e-2, -1e-2, 1e-2j])
    assert np.max(np.abs(ros_stability(zs, tab) - np.exp(zs))) < 1e-10  # e^z + O(z^5)
    assert_a_stable(tab)
