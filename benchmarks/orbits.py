"""Cost of one Newton solve for a periodic orbit against simulating periods (issue 10, sec. 6).

Standalone: ``python benchmarks/orbits.py [--repeat 3]``. For each case, from a converged
simulation (``stop="converged"``): the wall time of ``ssf.find_orbit`` (damped Newton on the
Poincare map with the variational Jacobian, rtol 1e-11), and of ``ssf.simulate`` over 20
periods from the same state at the same tolerances. Reports the Newton solve in "periods'
worth" of simulation (target: at most 20). Kernels are compiled by a warm-up call first; each
time is the minimum over ``--repeat`` runs. Prints one JSON line per case.

``--branch``: the full-branch cost (issue 10, sec. 6), side by side in one run: the period-1
orbit of Fig. 6 continued from eta = 2.0 in both directions over [1, 10] (``continue_orbit``,
ds 0.02, ds_max 0.05), once with ``sharp_ends=False`` (the stable part: it ends where the
default corrector stops, just short of the folds) and once with the default
``sharp_ends=True`` (through both folds and along the unstable sides to the precision
limit, docs/limits.md), steady sliding over [1, 10] (``continue_equilibrium``), and the
1000-value fixed-window Fig. 6 sweep on all cores (t_end 3000 / t_transient 2000). One run
each (the sweep and the branches are seconds to a minute, not milliseconds).
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


def branch_cost() -> dict:
    """Seconds for the Fig. 6 period-1 branch and sliding branch against the 1000-value sweep."""
    import numpy as np

    s = ssf.System.preset("asymmetric", eta=2.0)
    orbit = ssf.find_orbit(s, ssf.simulate(s, 3000.0, stop="converged"))
    ssf.continue_orbit(orbit, "eta", (1.9, 2.1), max_points=3)  # warm-up
    out: dict = {}
    for sharp, tag in ((False, "p1_stable"), (True, "p1_through_folds")):
        t0 = time.perf_counter()
        pts = 0
        for d in (-1.0, 1.0):
            b = ssf.continue_orbit(
                orbit, "eta", (1.0, 10.0), ds=0.02, ds_max=0.05, direction=d, sharp_ends=sharp
            )
            pts += b.values.size
            out[f"{tag}_{'down' if d < 0 else 'up'}"] = dict(
                points=int(b.values.size), end=float(b.values[-1]), status=b.status,
                folds=[x.value for x in b.bifurcations if x.kind == "fold"],
            )  # fmt: skip
        out[f"{tag}_s"] = time.perf_counter() - t0
        out[f"{tag}_points"] = pts
    t0 = time.perf_counter()
    e = ssf.find_equilibrium(s, "sliding")
    for d in (-1.0, 1.0):
        ssf.continue_equilibrium(e, "eta", (1.0, 10.0), ds=0.1, ds_max=0.5, direction=d)
    out["sliding_branch_s"] = time.perf_counter() - t0
    ssf.sweep(ssf.System.preset("asymmetric"), "eta", np.array([2.0]), t_end=10.0, progress=False)
    t0 = time.perf_counter()
    ssf.sweep(ssf.System.preset("asymmetric"), "eta", np.linspace(1.0, 10.0, 1000), t_end=3000.0,
              t_transient=2000.0, max_points=256, progress=False)  # fmt: skip
    out["fig6_sweep_1000_s"] = time.perf_counter() - t0
    for tag in ("p1_stable", "p1_through_folds"):
        out[f"{tag}_over_sweep"] = out[f"{tag}_s"] / out["fig6_sweep_1000_s"]
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--branch", action="store_true", help="also the full-branch cost")
    args = ap.parse_args()
    if args.branch:
        import warnings

        with warnings.catch_warnings():
            warnings.simplefilter("ignore", UserWarning)  # the sweep's equilibria
            print(json.dumps(dict(case="full branch vs 1000-value sweep", **branch_cost())))
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
