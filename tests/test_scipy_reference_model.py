"""Fast checks of the independent SciPy reference model (tests/reference/scipy_model.py)."""

from __future__ import annotations

import json
import sys
from pathlib import Path

import numpy as np
import pytest
from scipy.optimize import minimize_scalar

REF = Path(__file__).resolve().parent / "reference"
sys.path.insert(0, str(REF))

import scipy_model as sm  # noqa: E402

EPS = 1e-5


def _tmax(eta):
    """max_v T_s(v, 0, eps) written in u = v/eps (independent of eps)."""
    etap = sm.eta_prime(eta)

    def f(u):
        return u / np.sqrt(u * u + 1.0) + etap * u / (u * u + 1.0) ** 2

    u = np.linspace(1e-4, 60.0, 60001)
    i = int(np.argmax(f(u)))
    lo, hi = u[max(i - 1, 0)], u[min(i + 1, u.size - 1)]
    res = minimize_scalar(
        lambda z: -f(z), bounds=(lo, hi), method="bounded", options={"xatol": 1e-12}
    )
    return -res.fun, res.x


@pytest.mark.parametrize("eta", [*np.linspace(1.0, 10.0, 37).tolist(), 1.3, 2.7, 9.99])
def test_static_friction_peak_equals_eta(eta):
    peak, u = _tmax(eta)
    assert abs(peak - eta) < 1e-3, (eta, peak, u)
    # and the same through the model's own friction() at a real eps
    t, _ = sm.friction(u * EPS, 0.0, EPS, sm.eta_prime(eta))
    assert t == pytest.approx(peak, rel=1e-12)


def test_friction_odd_symmetry():
    rng = np.random.default_rng(1)
    v = rng.normal(scale=3 * EPS, size=200)
    w = rng.normal(scale=3 * EPS, size=200)
    for eta in (1.1, 2.0, 5.0, 9.99):
        ep = sm.eta_prime(eta)
        t, m = sm.friction(v, w, EPS, ep)
        t2, m2 = sm.friction(-v, -w, EPS, ep)
        np.testing.assert_allclose(t2, -t, rtol=0, atol=1e-15)
        np.testing.assert_allclose(m2, -m, rtol=0, atol=1e-15)
        # T_s odd in v / even in w, M_s odd in w / even in v
        t3, m3 = sm.friction(-v, w, EPS, ep)
        np.testing.assert_allclose(t3, -t, atol=1e-15)
        np.testing.assert_allclose(m3, m, atol=1e-15)
        t4, m4 = sm.friction(v, -w, EPS, ep)
        np.testing.assert_allclose(t4, t, atol=1e-15)
        np.testing.assert_allclose(m4, -m, atol=1e-15)
        assert sm.friction(0.0, 0.0, EPS, ep) == (0.0, 0.0)


@pytest.mark.parametrize("eta", [1.0, 1.5, 2.7, 8.0, 10.0])
def test_kinetic_limit(eta):
    ep = sm.eta_prime(eta)
    v = np.array([1e-2, 0.1, 1.0, -1e-2, -0.5])
    t, m = sm.friction(v, 0.0, EPS, ep)
    np.testing.assert_allclose(np.abs(t), 1.0, atol=1e-5)
    assert np.all(np.sign(t) == np.sign(v))
    np.testing.assert_array_equal(m, 0.0)
    # pure spin: |M_s| -> 2/3
    _, m = sm.friction(0.0, 0.3, EPS, ep)
    assert m == pytest.approx(2.0 / 3.0, abs=1e-6)


def test_eta_prime_pieces_continuous():
    for b in (1.3, 2.7):
        lo, hi = sm.eta_prime(b), sm.eta_prime(b + 1e-12)
        assert abs(lo - hi) < 2e-2  # the paper's fits join to ~1e-2
    with pytest.raises(ValueError):
        sm.eta_prime(0.5)


@pytest.mark.parametrize(
    "drive,n", [("constant", 1), ("constant", 3), ("dc-motor", 1), ("dc-motor", 2)]
)
def test_jacobian_matches_finite_differences(drive, n):
    p = dict(
        m=2.0,
        k12=-0.8,
        c=0.01,
        c12=0.003,
        mu=0.0491,
        eps=EPS,
        eta=3.0,
        drive=drive,
        vb=0.0112,
        vb0=0.0112,
        Tb=0.5,
        beta=0.0014,
        n_oscillators=n,
    )
    rng = np.random.default_rng(2)
    y = rng.normal(scale=2e-5, size=sm.state_size(p))
    if drive == "dc-motor":
        y[-1] = 0.0112 + 1e-5
    J = sm.jac(0.0, y, p)
    h = 1e-10
    cols = []
    for e in np.eye(y.size):
        cols.append((sm.rhs(0.0, y + h * e, p) - sm.rhs(0.0, y - h * e, p)) / (2 * h))
    Jn = np.column_stack(cols)
    np.testing.assert_allclose(J, Jn, rtol=1e-5, atol=1e-6 * np.max(np.abs(J)))


def test_rhs_layout_and_symmetric_invariance():
    p = dict(
        m=2.0,
        k12=0.0,
        c=0.0,
        c12=0.0,
        mu=0.0491,
        eps=EPS,
        eta=5.0,
        drive="dc-motor",
        vb=0.0112,
        vb0=0.0112,
        Tb=0.5,
        beta=0.0014,
        n_oscillators=2,
    )
    y = np.array([0.1, 0.02, 0.0, 0.0, -0.05, 0.03, 0.0, 0.0, 0.0112])
    d = sm.rhs(0.0, y, p)
    assert d[0] == y[1] and d[4] == y[5]
    assert d[2] == 0.0 and d[3] == 0.0 and d[6] == 0.0 and d[7] == 0.0
    # disks are decoupled except through vb: swapping disks swaps derivatives
    ys = np.concatenate([y[4:8], y[0:4], y[8:]])
    ds = sm.rhs(0.0, ys, p)
    np.testing.assert_allclose(ds, np.concatenate([d[4:8], d[0:4], d[8:]]), atol=1e-18)


def test_cheapest_case_reproduces_stored_prefix():
    cases = {c["name"]: c for c in json.loads((REF / "cases.json").read_text())}
    case = cases["sym_const_eta5"]
    with np.load(REF / "scipy_reference.npz") as ref:
        t_ref, y_ref = ref["sym_const_eta5__t"], ref["sym_const_eta5__y"]
    t_short = 140.0
    t, y = sm.scipy_poincare(case["params"], t_short, case["t_transient"], case["y0"])
    assert t.size >= 3
    k = t.size
    np.testing.assert_allclose(t, t_ref[:k], rtol=0, atol=1e-8)
    np.testing.assert_allclose(y, y_ref[:k], rtol=0, atol=1e-8)
