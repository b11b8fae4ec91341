"""Independent SciPy-only shooting: periodic orbits on the section dx1 = 0 (upward).

Uses only :mod:`scipy_model` (this directory) and SciPy, never ``stickslip_fast``:

* the p-th return map P^p is evaluated with ``solve_ivp`` (Radau, analytic Jacobian of
  the reference model, tight tolerances) and SciPy's event location of dx1 = 0 upward;
* its Jacobian in section coordinates (the state without dx1) by central finite
  differences of that map (no variational equations);
* the fixed point by plain Newton with that Jacobian; the multipliers are the
  eigenvalues of the finite-difference Jacobian at the fixed point.

``python tests/reference/scipy_shooting.py`` writes ``orbit_reference.json`` (about 2-4 min
on a 2-core box). Starts are the last Poincare point of the stored SciPy brute-force run
of the case (``scipy_reference.npz``) with x1 moved by 1e-4, so nothing comes from the
engine and Newton has to take steps.
"""

from __future__ import annotations

import json
import sys
import time
from pathlib import Path

import numpy as np
from scipy.integrate import solve_ivp

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))

from scipy_model import jac, rhs  # noqa: E402

RTOL, ATOL = 1e-12, 1e-14
FD_STEP = 1e-5
#: Added to x1 of the stored brute-force point before Newton starts.
START_OFFSET = 1e-4


def return_map(p, z, period=1, rtol=RTOL, atol=ATOL, t_max=1e3):
    """(P^p(z), time) for z on the section; z[1] is set to 0."""
    y = np.array(z, dtype=float)
    t_total = 0.0

    def ev(t, y):
        return y[1]

    ev.direction = 1.0
    ev.terminal = True
    for _ in range(period):
        y[1] = 0.0
        # leave the section first (SciPy reports a start on it as an event at t = 0)
        lead = 0.5
        s0 = solve_ivp(lambda t, y: rhs(t, y, p), (0.0, lead), y, method="Radau",
                       rtol=rtol, atol=atol, jac=lambda t, y: jac(t, y, p))  # fmt: skip
        if s0.status != 0 or s0.y[1, -1] <= 0.0:
            raise RuntimeError("the orbit does not leave the section upward within 0.5")
        sol = solve_ivp(lambda t, y: rhs(t, y, p), (lead, t_max), s0.y[:, -1], method="Radau",
                        rtol=rtol, atol=atol, jac=lambda t, y: jac(t, y, p), events=ev)  # fmt: skip
        if sol.status != 1:
            raise RuntimeError(f"no crossing before t_max: {sol.message}")
        y = np.array(sol.y_events[0][0], dtype=float)
        t_total += float(sol.t_events[0][0])
    return y, t_total


def fd_jacobian(p, z, period=1, h=FD_STEP):
    """Central finite differences of P^p in section coordinates (all but dx1)."""
    n = z.size
    idx = [i for i in range(n) if i != 1]
    J = np.empty((n - 1, n - 1))
    for c, i in enumerate(idx):
        zp = z.copy()
        zm = z.copy()
        zp[i] += h
        zm[i] -= h
        yp, _ = return_map(p, zp, period)
        ym, _ = return_map(p, zm, period)
        J[:, c] = (yp[idx] - ym[idx]) / (2 * h)
    return J


def shoot(p, z0, period=1, tol=1e-11, max_iter=8):
    """Newton on P^p(z) - z; returns (z, T, multipliers, residual, iterations)."""
    z = np.array(z0, dtype=float)
    z[1] = 0.0
    n = z.size
    idx = [i for i in range(n) if i != 1]
    it = 0
    while True:
        y, T = return_map(p, z, period)
        g = y[idx] - z[idx]
        res = float(np.max(np.abs(g)))
        J = fd_jacobian(p, z, period)
        if res <= tol or it >= max_iter:
            break
        z[idx] += np.linalg.solve(J - np.eye(n - 1), -g)
        it += 1
    mult = np.linalg.eigvals(J)
    mult = mult[np.argsort(-np.abs(mult))]
    return z, T, mult, res, it


def main() -> None:
    cases = {c["name"]: c for c in json.loads((HERE / "cases.json").read_text())}
    ref = np.load(HERE / "scipy_reference.npz")
    out = []
    for name, eta, period in (("asym_const_eta2", 2.0, 1), ("asym_const_eta999", 9.99, 2)):
        p = dict(cases[name]["params"], eta=eta)
        t0 = time.time()
        start = ref[f"{name}__y"][-1].copy()
        start[0] += START_OFFSET  # so that Newton has work to do
        z, T, mult, res, it = shoot(p, start, period)
        out.append(
            {
                "case": name,
                "params": p,
                "period": period,
                "point": z.tolist(),
                "T": T,
                "multipliers_real": mult.real.tolist(),
                "multipliers_imag": mult.imag.tolist(),
                "residual": res,
                "iterations": it,
                "rtol": RTOL,
                "atol": ATOL,
                "fd_step": FD_STEP,
                "start_offset_x1": START_OFFSET,
                "seconds": round(time.time() - t0, 1),
            }
        )
        print(out[-1])
    (HERE / "orbit_reference.json").write_text(json.dumps(out, indent=1) + "\n")


if __name__ == "__main__":
    main()
