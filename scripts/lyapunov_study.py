"""Largest Lyapunov exponent over eta for the literature parameter set.

Usage::

    python scripts/lyapunov_study.py [--n 40] [--t-transient 10000] [--t-end 40000]
        [--workers 2] [--csv docs/lyapunov_study.csv]

For each eta on a uniform grid over [1, 10] (plus the paper's eta = 2.7), runs
:func:`stickslip_fast.analysis.largest_lyapunov` and, as a cross-check, the
plain :func:`stickslip_fast.simulate` of the same trajectory (same y0 = 0,
t_end, t_transient, tolerances), whose Poincare points give the period. Prints
a Markdown table and writes a CSV.
"""

from __future__ import annotations

import argparse
import csv
import os
import sys
import time
from concurrent.futures import ProcessPoolExecutor

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))

import stickslip_fast as ssf  # noqa: E402
from stickslip_fast.analysis import largest_lyapunov  # noqa: E402

#: |exponent_fit| below this counts as zero, i.e. a periodic orbit.
ZERO_TOL = 1e-4
#: exponent above this counts as chaotic.
CHAOS_TOL = 1e-3


def verdict(lam: float, lam_fit: float, period: int) -> str:
    """Classify by the fit estimate (endpoint bias O(1/T^2)); Benettin's as a sanity check."""
    if abs(lam_fit) < ZERO_TOL and abs(lam) < CHAOS_TOL:
        return f"periodic (P{period})" if period else "periodic? (no period <= 64 found)"
    if min(lam, lam_fit) > CHAOS_TOL:
        return "chaotic" if not period else f"positive exponent but P{period}?!"
    if max(lam, lam_fit) < -ZERO_TOL:
        return "equilibrium/contracting"
    return f"unclear (P{period})" if period else "unclear"


def one(args: tuple[float, float, float]) -> dict:
    eta, t_transient, t_end = args
    system = ssf.System.preset("literature", eta=float(eta))
    res = largest_lyapunov(system, t_end, t_transient)
    t0 = time.perf_counter()
    sim = ssf.simulate(system, t_end, t_transient)
    t_sim = time.perf_counter() - t0
    return dict(
        eta=float(eta),
        exponent=res.exponent,
        exponent_fit=res.exponent_fit,
        status=res.status,
        period=sim.period,
        sim_status=sim.status,
        n_points=len(sim.t_poincare),
        lyap_steps=res.n_steps,
        sim_steps=sim.n_steps,
        lyap_s=res.runtime,
        sim_s=t_sim,
        verdict=verdict(res.exponent, res.exponent_fit, sim.period),
    )


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--n", type=int, default=40)
    ap.add_argument("--eta-min", type=float, default=1.0)
    ap.add_argument("--eta-max", type=float, default=10.0)
    ap.add_argument("--t-transient", type=float, default=10000.0)
    ap.add_argument("--t-end", type=float, default=40000.0)
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--csv", default="docs/lyapunov_study.csv")
    a = ap.parse_args()
    etas = np.linspace(a.eta_min, a.eta_max, a.n)
    if a.eta_min <= 2.7 <= a.eta_max:
        etas = np.concatenate([etas, [2.7]])
    etas = np.unique(np.round(etas, 6))
    # compile (or load the cache) once before forking
    largest_lyapunov(ssf.System.preset("literature", eta=2.7), 10.0, 1.0)
    ssf.simulate(ssf.System.preset("literature", eta=2.7), 10.0, 1.0)
    t0 = time.perf_counter()
    with ProcessPoolExecutor(a.workers) as ex:
        rows = list(ex.map(one, [(e, a.t_transient, a.t_end) for e in etas]))
    wall = time.perf_counter() - t0
    print(
        "| eta | exponent | exponent_fit | simulate status | period | verdict | Lyapunov s | simulate s |"
    )
    print("|---|---|---|---|---|---|---|---|")
    for r in rows:
        print(
            f"| {r['eta']:.4f} | {r['exponent']:.2e} | {r['exponent_fit']:.2e} | {r['sim_status']} "
            f"| {r['period']} "
            f"| {r['verdict']} | {r['lyap_s']:.2f} | {r['sim_s']:.2f} |"
        )
    lt = sum(r["lyap_s"] for r in rows)
    st = sum(r["sim_s"] for r in rows)
    ls = sum(r["lyap_steps"] for r in rows)
    ss = sum(r["sim_steps"] for r in rows)
    print(
        f"\n{len(rows)} values, wall {wall:.1f} s on {a.workers} workers; kernel totals: "
        f"Lyapunov {lt:.1f} s / {ls} steps, simulate {st:.1f} s / {ss} steps"
    )
    if a.csv:
        os.makedirs(os.path.dirname(a.csv) or ".", exist_ok=True)
        with open(a.csv, "w", newline="") as fh:
            w = csv.DictWriter(fh, fieldnames=list(rows[0]))
            w.writeheader()
            w.writerows(rows)


if __name__ == "__main__":
    main()
