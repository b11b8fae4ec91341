"""Independent SciPy reference model of the translational-rotational stick-slip oscillator.

Written directly from the (nondimensional) equations of the paper, Sections 2-3:

    x_i'' + c x_i' + c12 phi_i' + x_i + k12 phi_i + mu T_s(x_i' - v_b, phi_i', eps) = 0
    m phi_i'' + c12 x_i' + c phi_i' + k12 x_i + phi_i + mu M_s(x_i' - v_b, phi_i', eps) = 0

    T_s(v, w, eps) = v * B,   M_s(v, w, eps) = (2/3) w * B,
    B = 1/sqrt(s) + eta' eps^3 / s^2,   s = v^2 + w^2 + eps^2

Drive "constant": v_b is a parameter. Drive "dc-motor": v_b is the last state and
    T_b v_b' + v_b = v_b0 + (beta/N) sum_i T_s(x_i' - v_b, phi_i', eps).

State layout: [x1, dx1, phi1, dphi1, x2, dx2, phi2, dphi2, ..., (vb if dc-motor)].

This module deliberately does not import anything from ``stickslip_fast``; it is used by the
test suite to cross-check the Numba engine.
"""

from __future__ import annotations

import numpy as np
from scipy.integrate import solve_ivp

PARAM_KEYS = (
    "m",
    "k12",
    "c",
    "c12",
    "mu",
    "eps",
    "eta",
    "drive",
    "vb",
    "vb0",
    "Tb",
    "beta",
    "n_oscillators",
)


def eta_prime(eta: float) -> float:
    """Piecewise-cubic map eta (static/kinetic ratio) -> eta' (paper, Sec. 2)."""
    eta = float(eta)
    if eta < 1.0 or eta > 10.0:
        raise ValueError(f"eta={eta} outside the fitted range [1, 10]")
    if eta <= 1.3:
        a = (-13.607, 30.893, -22.01, 5.878)
    elif eta <= 2.7:
        a = (-2.41, 3.985, -0.3581, 0.0493)
    else:
        a = (-1.684, 3.121, -0.00483, 0.000196)
    return a[0] + a[1] * eta + a[2] * eta**2 + a[3] * eta**3


def friction(v, w, eps, etap):
    """Return (T_s, M_s) for slip velocity v, angular slip w (numpy broadcasting)."""
    s = v * v + w * w + eps * eps
    b = 1.0 / np.sqrt(s) + etap * eps**3 / (s * s)
    return v * b, (2.0 / 3.0) * w * b


def friction_jac(v, w, eps, etap):
    """Return (T, M, dT/dv, dT/dw, dM/dv, dM/dw)."""
    s = v * v + w * w + eps * eps
    rs = np.sqrt(s)
    b = 1.0 / rs + etap * eps**3 / (s * s)
    db_ds = -0.5 / (s * rs) - 2.0 * etap * eps**3 / (s * s * s)
    t = v * b
    mm = (2.0 / 3.0) * w * b
    t_v = b + 2.0 * v * v * db_ds
    t_w = 2.0 * v * w * db_ds
    m_v = (2.0 / 3.0) * 2.0 * v * w * db_ds
    m_w = (2.0 / 3.0) * (b + 2.0 * w * w * db_ds)
    return t, mm, t_v, t_w, m_v, m_w


def _is_dc(p) -> bool:
    d = str(p["drive"]).lower().replace("_", "-")
    if d in ("dc-motor", "dc", "dcmotor"):
        return True
    if d == "constant":
        return False
    raise ValueError(f"unknown drive {p['drive']!r}")


def state_size(p) -> int:
    return 4 * int(p["n_oscillators"]) + (1 if _is_dc(p) else 0)


def rhs(t, y, p):
    """Right-hand side dy/dt for the state layout described in the module docstring."""
    n = int(p["n_oscillators"])
    dc = _is_dc(p)
    etap = eta_prime(p["eta"])
    m, k12, c, c12 = p["m"], p["k12"], p["c"], p["c12"]
    mu, eps = p["mu"], p["eps"]
    y = np.asarray(y, dtype=float)
    q = y[: 4 * n].reshape(n, 4)
    x, dx, ph, dph = q[:, 0], q[:, 1], q[:, 2], q[:, 3]
    vb = y[4 * n] if dc else p["vb"]
    ts, ms = friction(dx - vb, dph, eps, etap)
    out = np.empty_like(y)
    o = out[: 4 * n].reshape(n, 4)
    o[:, 0] = dx
    o[:, 1] = -(c * dx + c12 * dph + x + k12 * ph + mu * ts)
    o[:, 2] = dph
    o[:, 3] = -(c12 * dx + c * dph + k12 * x + ph + mu * ms) / m
    if dc:
        out[4 * n] = (p["vb0"] + p["beta"] / n * np.sum(ts) - vb) / p["Tb"]
    return out


def jac(t, y, p):
    """Analytic Jacobian of :func:`rhs` (checked against finite differences in the tests)."""
    n = int(p["n_oscillators"])
    dc = _is_dc(p)
    etap = eta_prime(p["eta"])
    m, k12, c, c12 = p["m"], p["k12"], p["c"], p["c12"]
    mu, eps = p["mu"], p["eps"]
    y = np.asarray(y, dtype=float)
    ns = y.size
    J = np.zeros((ns, ns))
    vb = y[4 * n] if dc else p["vb"]
    for i in range(n):
        k = 4 * i
        dx, dph = y[k + 1], y[k + 3]
        _, _, t_v, t_w, m_v, m_w = friction_jac(dx - vb, dph, eps, etap)
        J[k, k + 1] = 1.0
        J[k + 1, k] = -1.0
        J[k + 1, k + 1] = -(c + mu * t_v)
        J[k + 1, k + 2] = -k12
        J[k + 1, k + 3] = -(c12 + mu * t_w)
        J[k + 2, k + 3] = 1.0
        J[k + 3, k] = -k12 / m
        J[k + 3, k + 1] = -(c12 + mu * m_v) / m
        J[k + 3, k + 2] = -1.0 / m
        J[k + 3, k + 3] = -(c + mu * m_w) / m
        if dc:
            iv = 4 * n
            J[k + 1, iv] = mu * t_v
            J[k + 3, iv] = mu * m_v / m
            J[iv, k + 1] = p["beta"] / n * t_v / p["Tb"]
            J[iv, k + 3] = p["beta"] / n * t_w / p["Tb"]
            J[iv, iv] += -p["beta"] / n * t_v / p["Tb"]
    if dc:
        J[4 * n, 4 * n] += -1.0 / p["Tb"]
    return J


def scipy_poincare(
    p,
    t_end,
    t_transient,
    y0,
    method="Radau",
    rtol=1e-10,
    atol=1e-12,
    use_jac=True,
    max_step=np.inf,
    return_sol=False,
):
    """Poincare points at local minima of x_1 (dx_1 crosses 0 upward), for t >= t_transient.

    Crossings are located by SciPy's event root finding on the dense output.
    Returns (t_points, y_points) with y_points of shape (n_points, state_size).
    """
    y0 = np.asarray(y0, dtype=float)
    if y0.size != state_size(p):
        raise ValueError(f"y0 has {y0.size} entries, expected {state_size(p)}")

    def ev(t, y):
        return y[1]

    ev.direction = 1.0
    ev.terminal = False

    kw = {}
    if use_jac and method in ("Radau", "BDF", "LSODA"):
        kw["jac"] = lambda t, y: jac(t, y, p)
    sol = solve_ivp(
        lambda t, y: rhs(t, y, p),
        (0.0, float(t_end)),
        y0,
        method=method,
        rtol=rtol,
        atol=atol,
        events=ev,
        max_step=max_step,
        **kw,
    )
    if sol.status != 0:
        raise RuntimeError(f"solve_ivp failed: {sol.message}")
    te = np.asarray(sol.t_events[0], dtype=float)
    ye = np.asarray(sol.y_events[0], dtype=float).reshape(te.size, y0.size)
    # A start exactly at dx1 = 0 (e.g. y0 = 0) is reported by SciPy as an event at t = 0;
    # it is not a local minimum reached from dx1 < 0, so it is never recorded.
    keep = (te >= float(t_transient)) & (te > 0.0)
    if return_sol:
        return te[keep], ye[keep], sol
    return te[keep], ye[keep]
