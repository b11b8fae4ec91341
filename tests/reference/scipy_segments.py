"""Independent SciPy check of a periodic orbit given as segments (multiple shooting).

Uses only :mod:`scipy_model` (this directory), NumPy and SciPy, never ``stickslip_fast``.
An orbit of period T cut at the fractions ``mesh`` (0 = mesh[0] < ... < mesh[m] = 1)
with segment starts ``starts`` (m, n) is checked by integrating every segment on its own
with ``solve_ivp`` (Radau) together with its variational equations (the reference
model's analytic Jacobian), from the given start over its own time span:

* the **continuity residual** of each junction: |phi_i(starts[i]) - starts[i + 1]|, the
  last segment closing on starts[0]. For a very unstable orbit (multiplier 1e16 and
  more) one trajectory over the whole period cannot be integrated to any accuracy in
  double precision, but each segment amplifies little, so each is checked to about
  SciPy's own accuracy;
* the **leading multiplier** of the product of the segments' monodromies
  M = Phi_{m-1} ... Phi_0, by orthogonal iteration: Q is carried through the factors and
  re-orthonormalised by QR after each one; once converged, the sum over one period of
  log|R_11| is log|mu_1|. The product is never formed, so it cannot overflow, and the
  algorithm is not the engine's (a periodic Schur decomposition).
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
from scipy.integrate import solve_ivp

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))

from scipy_model import jac, rhs  # noqa: E402


def _augmented(t, w, p, n):
    """The state and its variational equations, Phi' = J(y) Phi."""
    y, Phi = w[:n], w[n:].reshape(n, n)
    out = np.empty_like(w)
    out[:n] = rhs(t, y, p)
    out[n:] = (jac(t, y, p) @ Phi).ravel()
    return out


def _augmented_jac(t, w, p, n, step=1e-10):
    """The Jacobian of :func:`_augmented` (d(J Phi)/dy by central differences of J: it
    only steers Radau's Newton iteration; without it, stick phases cost 50 times more)."""
    y, Phi = w[:n], w[n:].reshape(n, n)
    J = jac(t, y, p)
    A = np.zeros((n + n * n, n + n * n))
    A[:n, :n] = J
    for k in range(n):
        e = np.zeros(n)
        e[k] = step
        dJ = (jac(t, y + e, p) - jac(t, y - e, p)) / (2.0 * step)
        A[n:, k] = (dJ @ Phi).ravel()
    for r in range(n):  # entry (r, c) of J Phi depends on column c of Phi through row r of J
        for c in range(n):
            A[n + r * n + c, n + c :: n] = J[r]
    return A


def flow_segment(p, y0, tau, rtol=1e-10, atol=1e-12):
    """(phi(y0, tau), Phi): the state after time ``tau`` from ``y0`` and its monodromy."""
    n = len(y0)
    w0 = np.r_[np.asarray(y0, dtype=float), np.eye(n).ravel()]
    sol = solve_ivp(_augmented, (0.0, float(tau)), w0, method="Radau", rtol=rtol, atol=atol,
                    args=(p, n), jac=_augmented_jac)  # fmt: skip
    if not sol.success:
        raise RuntimeError(f"solve_ivp failed: {sol.message}")
    w = sol.y[:, -1]
    return w[:n], w[n:].reshape(n, n)


def leading_multiplier(factors, sweeps: int = 30) -> float:
    """|mu_1| of factors[-1] @ ... @ factors[0], by orthogonal iteration (no product formed)."""
    n = factors[0].shape[0]
    q = np.eye(n)[:, :1]
    log_growth = 0.0
    for _ in range(sweeps):
        log_growth = 0.0
        for M in factors:
            q, r = np.linalg.qr(M @ q)
            log_growth += np.log(abs(r[0, 0]))
    return float(np.exp(log_growth))


def check_segments(p, mesh, starts, T, rtol=1e-10, atol=1e-12):
    """Integrate every segment, and its monodromy, independently.

    Returns
    -------
    dict
        ``residuals`` (m,): max-norm continuity residual of each junction (the last one
        closes the period on starts[0]); ``residual``: their maximum; ``factors``: the
        segments' monodromies; ``norms``: their 2-norms; ``mu1``: |leading multiplier|
        of their product.
    """
    mesh = np.asarray(mesh, dtype=float)
    starts = np.asarray(starts, dtype=float)
    m = mesh.size - 1
    residuals, factors = np.empty(m), []
    for i in range(m):
        y1, Phi = flow_segment(p, starts[i], (mesh[i + 1] - mesh[i]) * T, rtol, atol)
        residuals[i] = float(np.max(np.abs(y1 - starts[(i + 1) % m])))
        factors.append(Phi)
    return {
        "residuals": residuals,
        "residual": float(residuals.max()),
        "factors": factors,
        "norms": np.array([np.linalg.norm(F, 2) for F in factors]),
        "mu1": leading_multiplier(factors),
    }


def sample_segments(p, mesh, starts, T, n_samples=20000, rtol=1e-10, atol=1e-12):
    """The orbit sampled about ``n_samples`` times a period, each segment from its own start
    (states, shape (k, n)): one trajectory over the period would leave a very unstable
    orbit long before its end."""
    mesh = np.asarray(mesh, dtype=float)
    out = []
    for i in range(mesh.size - 1):
        tau = (mesh[i + 1] - mesh[i]) * T
        sol = solve_ivp(rhs, (0.0, tau), np.asarray(starts[i], dtype=float), method="Radau",
                        rtol=rtol, atol=atol, args=(p,), jac=jac, dense_output=True)  # fmt: skip
        if not sol.success:
            raise RuntimeError(f"solve_ivp failed: {sol.message}")
        k = max(20, int(round(n_samples * tau / T)))
        out.append(sol.sol(np.linspace(0.0, tau, k, endpoint=False)).T)
    return np.concatenate(out)
