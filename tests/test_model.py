"""The friction law's own claims and the analytic Jacobian."""

import numpy as np
import pytest
from scipy.optimize import minimize_scalar

from stickslip_fast import System
from stickslip_fast.model.equations import dense_jacobian, eta_prime, friction, rhs


def _peak_of_T(eta: float, eps: float = 1e-5) -> float:
    """max over v of T_s(v, 0, eps), found by SciPy on u = v / eps."""
    etap = eta_prime(eta)
    # coarse scan for the bracket, then a bounded scalar minimisation
    u = np.linspace(1e-3, 5.0, 5001)
    vals = np.array([friction(x * eps, 0.0, eps, etap)[0] for x in u])
    u0 = u[np.argmax(vals)]
    res = minimize_scalar(
        lambda x: -friction(x * eps, 0.0, eps, etap)[0],
        bounds=(max(1e-6, u0 - 0.01), u0 + 0.01),
        method="bounded",
        options={"xatol": 1e-12},
    )
    return -res.fun


@pytest.mark.parametrize("eta", np.round(np.linspace(1.0, 10.0, 91), 6))
def test_static_friction_peak_equals_eta(eta):
    # the paper: |max T_s - eta| < 0.001 over the whole fitted range
    assert abs(_peak_of_T(eta) - eta) < 1e-3


def test_peak_is_independent_of_eps():
    for eps in (1e-3, 1e-5, 1e-7):
        assert abs(_peak_of_T(4.0, eps) - 4.0) < 1e-3


def test_eta_prime_pieces_and_range():
    # the paper's three cubics, evaluated independently
    assert eta_prime(1.2) == pytest.approx(-13.607 + 30.893 * 1.2 - 22.01 * 1.44 + 5.878 * 1.728)
    assert eta_prime(2.0) == pytest.approx(-2.41 + 3.985 * 2 - 0.3581 * 4 + 0.0493 * 8)
    assert eta_prime(9.0) == pytest.approx(-1.684 + 3.121 * 9 - 0.00483 * 81 + 0.000196 * 729)
    assert eta_prime(1.0) == pytest.approx(1.154, abs=1e-12)
    assert np.isnan(eta_prime(0.99)) and np.isnan(eta_prime(10.01))


def test_friction_is_odd_and_tends_to_coulomb():
    rng = np.random.default_rng(1)
    eps, etap = 1e-5, eta_prime(3.3)
    for _ in range(200):
        v, w = rng.normal(scale=3e-5, size=2)
        t1, m1 = friction(v, w, eps, etap)
        t2, m2 = friction(-v, -w, eps, etap)
        assert t2 == -t1 and m2 == -m1
        t3, m3 = friction(-v, w, eps, etap)
        assert t3 == -t1 and m3 == m1
    # |v| >> eps, w = 0: T -> sign(v), the kinetic (Coulomb) limit
    for v in (1e-2, 0.3, -0.5, 10.0):
        t, m = friction(v, 0.0, eps, etap)
        assert t == pytest.approx(np.sign(v), abs=1e-6) and m == 0.0
    # pure spin |w| >> eps: M -> (2/3) sign(w) (Contensou's torque limit)
    t, m = friction(0.0, 0.2, eps, etap)
    assert t == 0.0 and m == pytest.approx(2 / 3, abs=1e-6)
    # combined slip: the force direction follows the slip velocity
    t, m = friction(0.3, 0.4, eps, etap)
    assert t == pytest.approx(0.6, rel=1e-8) and m == pytest.approx(2 / 3 * 0.8, rel=1e-8)


def _fd_jacobian(y, p, n_osc, dc):
    n = y.size
    jac = np.zeros((n, n))
    f1 = np.empty(n)
    f2 = np.empty(n)
    for k in range(n):
        h = 1e-7 * max(1e-3, abs(y[k]))
        yp, ym = y.copy(), y.copy()
        yp[k] += h
        ym[k] -= h
        rhs(yp, p, n_osc, dc, f1)
        rhs(ym, p, n_osc, dc, f2)
        jac[:, k] = (f1 - f2) / (2 * h)
    return jac


@pytest.mark.parametrize("n_osc", [1, 2, 5])
@pytest.mark.parametrize("drive", ["constant", "dc-motor"])
def test_jacobian_matches_finite_differences(n_osc, drive):
    rng = np.random.default_rng(n_osc)
    sysm = System.preset(
        "asymmetric", drive=drive, n_oscillators=n_osc, eps=1e-2, eta=3.7, c=0.03, c12=0.01
    )
    p = sysm.to_array()
    for _ in range(5):
        y = rng.normal(scale=0.05, size=sysm.n_state)
        if drive == "dc-motor":
            y[-1] = 0.01 + 0.01 * rng.random()
        jac = dense_jacobian(y, p, n_osc, drive == "dc-motor")
        fd = _fd_jacobian(y, p, n_osc, drive == "dc-motor")
        np.testing.assert_allclose(jac, fd, rtol=1e-6, atol=1e-6 * np.abs(fd).max())
        # the bordered structure: disks couple only through the belt speed
        for i in range(n_osc):
            for j in range(n_osc):
                if i != j:
                    assert np.all(jac[4 * i : 4 * i + 4, 4 * j : 4 * j + 4] == 0)


def test_jacobian_stiffness_at_stick():
    # largest eigenvalue magnitude ~ mu (1 + eta') / eps while the disk sticks
    s = System.preset("asymmetric", eta=5.0)
    y = np.array([0.01, s.vb, 0.0, 0.0])
    lam = np.abs(np.linalg.eigvals(dense_jacobian(y, s.to_array(), 1, False))).max()
    expected = s.mu * (1 + eta_prime(5.0)) / s.eps
    assert lam == pytest.approx(expected, rel=0.02)


def _rhs_as_written(y, s: System) -> np.ndarray:
    """The paper's Eq. 15 for one disk on a constant belt, term by term as printed, in
    extended precision: the reference for the engine's latency-arranged arithmetic."""
    x, dx, ph, dph = (np.longdouble(v) for v in y)
    eps, etap, vb = np.longdouble(s.eps), np.longdouble(eta_prime(s.eta)), np.longdouble(s.vb)
    v, w = dx - vb, dph
    q = v * v + w * w + eps * eps
    g = 1 / np.sqrt(q) + etap * eps**3 / q**2
    t, m_s = v * g, np.longdouble(2) / 3 * w * g
    ddx = -(s.c * dx + s.c12 * dph) - (x + s.k12 * ph) - s.mu * t
    ddph = (-(s.c12 * dx + s.c * dph) - (s.k12 * x + ph) - s.mu * m_s) / s.m
    return np.array([dx, ddx, dph, ddph], dtype=np.longdouble)


def test_rhs_matches_the_equation_as_written_and_the_peers_copy():
    # the right-hand side is arranged for latency (a reciprocal beside the square root,
    # 1/m as a factor): the same function to within a few ulps of the largest term, at
    # slips from deep in the stick phase (|v| ~ eps / 100) to fast sliding; the benchmark
    # peers' own copy (benchmarks/peers.py) likewise, so they integrate the same model
    from benchmarks.peers import params, rhs1

    rng = np.random.default_rng(7)
    for eta in (1.2, 3.3, 9.99):
        s = System.preset("asymmetric", eta=eta).replace(c=0.01, c12=0.003)
        p, p1 = s.to_array(), params(s.to_dict())
        for scale in (1e-7, 1e-5, 1e-3, 0.3):
            for _ in range(50):
                y = rng.normal(scale=0.1, size=4)
                y[1] = s.vb + rng.normal(scale=scale)
                y[3] = rng.normal(scale=scale)
                ref = _rhs_as_written(y, s)
                size = float(np.max(np.abs(ref))) + 1.0
                out, out1 = np.empty(4), np.empty(4)
                rhs(y, p, 1, False, out)
                rhs1(y, p1, out1)
                assert np.max(np.abs(out - ref)) < 8 * np.finfo(float).eps * size
                assert np.max(np.abs(out1 - ref)) < 8 * np.finfo(float).eps * size
