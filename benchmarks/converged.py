"""Converged stopping against the fixed window: the Fig. 6 sweep both ways, side by side.

The full run times the paper's Fig. 6 diagram (asymmetric springs, constant
belt, 1000 values of eta in [1, 10], t_end 3000 / t_transient 2000) with
``stop="fixed"`` and ``stop="converged"`` (same t_end as the cap), alternating
the two, best of ``repeats``; it also reports how many values agree in status
and period. ``--quick``: 60 values, one repetition.
"""

from __future__ import annotations

import time

import numpy as np

import stickslip_fast as ssf


def run(mode: str, log) -> dict:
    quick = mode == "quick"
    n_values = 60 if quick else 1000
    repeats = 1 if quick else 3
    system = ssf.System.preset("asymmetric")
    values = np.linspace(1.0, 10.0, n_values)
    kw = dict(t_end=3000.0, t_transient=2000.0, max_points=256, progress=False)
    ssf.sweep(system, "eta", values[:4], stop="converged", **kw)  # compile outside the timing
    times = {"fixed": [], "converged": []}
    results = {}
    for rep in range(repeats):
        for stop in ("fixed", "converged"):
            t0 = time.perf_counter()
            results[stop] = ssf.sweep(system, "eta", values, stop=stop, **kw)
            times[stop].append(time.perf_counter() - t0)
            log(f"   {stop}: {times[stop][-1]:.1f} s (repetition {rep + 1})")
    fixed, conv = results["fixed"], results["converged"]
    same = (fixed.status == conv.status) & (fixed.period == conv.period)
    tc = conv.t_converged
    best = {k: min(v) for k, v in times.items()}
    return dict(
        n_values=n_values,
        repeats=repeats,
        seconds=times,
        best_fixed=best["fixed"],
        best_converged=best["converged"],
        speedup=best["fixed"] / best["converged"],
        steps_fixed=int(fixed.n_steps.sum()),
        steps_converged=int(conv.n_steps.sum()),
        agree_status_period=int(same.sum()),
        not_converged=int(np.count_nonzero(~np.isfinite(tc))),
        median_t_converged=float(np.nanmedian(tc)),
    )
