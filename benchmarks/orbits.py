"""Cost of one Newton solve for a periodic orbit against simulating periods (issue 10, sec. 6).

Standalone: ``python benchmarks/orbits.py [--repeat 3]``. For each case, from a converged
simulation (``stop="converged"``): the wall time of ``ssf.find_orbit`` (damped Newton on the
Poincare map with the variational Jacobian, rtol 1e-11), and of ``ssf.simulate`` over 20
periods from the same state at the same tolerances. Reports the Newton solve in "periods'
worth" of simulation (target: at most 20). Kernels are compiled by a warm-up call first; each
time is the minimum over ``--repeat`` runs. Prints one JSON line per case.
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
if str(ROOT) not in sys.path:  # benchmark this checkout, not an installed copy
    sys.path.insert(0, str(ROOT))

import stickslip_fast as ssf  # noqa: E402

CASES = (("asymmetric eta=2.0 P1", 2.0), ("asymmetric eta=9.99 P2", 9.99))
N_PERIODS = 20


def _best(fn, repeat):
    best, out = float("inf"), None
    for _ in range(repeat):
        t0 = time.perf_counter()
        out = fn()
        best = min(best, time.perf_counter() - t0)
    return best, out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--repeat", type=int, default=3)
    args = ap.parse_args()
    for name, eta in CASES:
        s = ssf.System.preset("asymmetric", eta=eta)
        r = ssf.simulate(s, 20000, stop="converged")
        ssf.find_orbit(s, r)  # warm-up (compilation)
        t_newton, orbit = _best(lambda s=s, r=r: ssf.find_orbit(s, r), args.repeat)
        t_end = N_PERIODS * orbit.T
        t_sim, _ = _best(
            lambda s=s, r=r, t_end=t_end: ssf.simulate(
                s, t_end, y0=r.final_state, rtol=1e-11, atol=1e-13, max_points=64
            ),
            args.repeat,
        )
        per_period = t_sim / N_PERIODS
        print(
            json.dumps(
                dict(
                    case=name,
                    period=orbit.period,
                    status=orbit.status,
                    iterations=orbit.iterations,
                    residual=orbit.residual,
                    newton_s=round(t_newton, 4),
                    simulate_20_periods_s=round(t_sim, 4),
                    newton_in_periods=round(t_newton / per_period, 2),
                    target_periods=N_PERIODS,
                )
            )
        )


if __name__ == "__main__":
    main()
