"""Converged stopping against the fixed window: the Fig. 6 sweep both ways, side by side.

The full run times the paper's Fig. 6 diagram (asymmetric springs, constant
belt, 1000 values of eta in [1, 10], t_end 3000 / t_transient 2000) with
``stop="fixed"`` and ``stop="converged"`` (same t_end as the cap), alternating
the two, best of ``repeats``; it also reports how many values agree in status
and period. ``--quick``: 60 values, one repetition.

It also times the fixed sweep on the generic kernel (the engine before the small-N
kernel of issue 11; bit-identical results, checked). It then measures the census cost
per start on Fig. 6 (issue 9): a 64-start
census (converged stopping, cap 3000) on every 10th value of a 200-value grid
of eta in [1, 10], timed once; the cost of the 200-value census is projected
from it (the values are an even stride of that grid, so their cost per value
is representative) and set against the 1000-value fixed-window sweep timed
above. ``--quick``: 2 values x 16 starts.
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
    # quick mode (the CI smoke test) skips it: one more compiled kernel, ~40 s
    generic_s = None if quick else fixed_sweep_generic(system, values, kw, results["fixed"], log)
    census = census_cost(system, quick, best["fixed"], n_values, log, generic_s)
    return dict(
        census=census,
        fixed_generic_kernel_s=generic_s,
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


def fixed_sweep_generic(system, values, kw, fixed_result, log) -> float:
    """The fixed-window sweep on the generic kernel: the engine as the census issue found it.

    Since the small-N kernel (issue 11) a one-disk sweep runs on
    ``problems.StickSlipSmall``; the generic bordered kernel it replaced is still there
    (larger N use it) and gives bit-identical results. Until the driver borrowed its
    records (2026-11-23) this was "today's 1000-value fixed sweep" of the census issue's
    cost target; since then the generic kernel is ~4x faster too (docs/census.md).
    """
    from stickslip_fast.backends import local as chunks

    small = chunks.kernel_variant
    chunks.kernel_variant = lambda n_osc, dc: ()
    try:
        ssf.sweep(system, "eta", values[:2], stop="fixed", **kw)  # compile outside the timing
        t0 = time.perf_counter()
        res = ssf.sweep(system, "eta", values, stop="fixed", **kw)
        dt = time.perf_counter() - t0
    finally:
        chunks.kernel_variant = small
    identical = bool(
        np.array_equal(res.points, fixed_result.points, equal_nan=True)
        and np.array_equal(res.n_steps, fixed_result.n_steps)
    )
    log(f"   fixed, generic kernel: {dt:.1f} s (results bit-identical: {identical})")
    if not identical:
        raise RuntimeError(
            "the generic and the small-N kernel disagree: see tests/test_small_kernel.py"
        )
    return dt


def census_cost(
    system, quick: bool, fixed_s: float, fixed_values: int, log, generic_s: float | None = None
) -> dict:
    """Seconds per start of a Fig. 6 census, and a 200-value census against the fixed sweep.

    ``generic_s``: the same fixed sweep on the generic kernel (bit-identical results).
    """
    grid = np.linspace(1.0, 10.0, 200)
    values = grid[::100] if quick else grid[::10]
    n_starts = 16 if quick else 64
    kw = dict(t_end=3000.0, max_points=128, stop="converged", progress=False)
    ssf.census(system, "eta", values[:1], n_starts=2, **kw)  # compiled outside the timing
    t0 = time.perf_counter()
    res = ssf.census(system, "eta", values, n_starts=n_starts, **kw)
    dt = time.perf_counter() - t0
    runs = values.size * n_starts
    projected = dt / values.size * grid.size * (64 / n_starts)
    log(f"   census: {values.size} values x {n_starts} starts in {dt:.1f} s "
        f"({1e3 * dt / runs:.1f} ms per start); 200 x 64 projected {projected:.0f} s "
        f"against the {fixed_values}-value fixed sweep's {fixed_s:.1f} s")  # fmt: skip
    return dict(
        values=int(values.size),
        n_starts=int(n_starts),
        seconds=dt,
        ms_per_start=1e3 * dt / runs,
        runs_without_attractor=int(np.count_nonzero(res.labels < 0)),
        projected_200x64_s=projected,
        fixed_sweep_s=fixed_s,
        fixed_sweep_values=int(fixed_values),
        ratio_to_fixed_sweep=projected / fixed_s,
        fixed_sweep_generic_kernel_s=generic_s,
        ratio_to_fixed_sweep_generic_kernel=None if generic_s is None else projected / generic_s,
        target="a 64-start census of 200 values costs no more than the 1000-value fixed sweep",
    )
