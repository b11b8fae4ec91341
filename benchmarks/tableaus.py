"""The engine's Rosenbrock tableaus side by side, at matched Poincare accuracy.

Asymmetric preset, constant belt, eta = 2.0 and 9.99, from rest to t = 1500, points
after t = 1000, against the SciPy Radau rtol 1e-12 reference of
:mod:`benchmarks.peer_precision`. For each method and each target error (1e-6, 1e-8)
the rtol is the first rung of the same ladder (atol = 0.01 rtol) whose run puts every
point within the target. Then the chosen runs are timed in alternating rounds (one
method after the other), best of the rounds, one core. The same runs give the steps and
the cost per attempted step, so the result splits into "fewer stages per step" against
"more steps for the same accuracy".

This is the measurement behind the default: ``rodas5p`` stays the default, and no
automatic choice by tolerance is made, unless a lower-order tableau wins here.
"""

from __future__ import annotations

import math
import time

from .common import ssf
from .peer_precision import ATOL_FACTOR, CASES, LADDER, TARGETS, point_error
from .reference import trajectory_reference

METHODS = ("rodas5p", "rodas4p", "rodas4p2")
SETTINGS = {
    "full": dict(rounds=5, targets=TARGETS, ladder=LADDER, cases=CASES["full"]),
    "quick": dict(rounds=1, targets=(1e-6,), ladder=[1e-6, 3e-7, 1e-7], cases=CASES["quick"]),
}


def _simulate(system, tr, method, rtol):
    return ssf.simulate(
        system, tr["t_end"], tr["t_transient"], method=method, rtol=rtol,
        atol=ATOL_FACTOR * rtol, max_points=10_000,
    )  # fmt: skip


def run(mode: str, log) -> dict:
    """Scan the ladder per method, then time the cheapest accurate run of each."""
    settings = SETTINGS[mode]
    res = dict(
        methods=list(METHODS),
        settings=dict(
            rounds=settings["rounds"],
            targets=list(settings["targets"]),
            ladder=list(settings["ladder"]),
            atol_factor=ATOL_FACTOR,
        ),
        cores_used=1,
        cases={},
    )
    for tr in settings["cases"]:
        system = ssf.System.preset("asymmetric", eta=tr["eta"])
        ref = trajectory_reference(tr["eta"], tr["t_end"], tr["t_transient"], log=log)
        for m in METHODS:  # compile outside the timing
            _simulate(system, dict(tr, t_end=20.0, t_transient=10.0), m, 1e-6)
        scans, chosen = {}, {}
        for m in METHODS:
            scan, need = [], set(settings["targets"])
            for rtol in settings["ladder"]:
                r = _simulate(system, tr, m, rtol)
                if r.status == "ok":
                    err, note = point_error(ref["t"], ref["points"], r.t_poincare, r.poincare)
                else:
                    err, note = math.inf, r.status
                scan.append(
                    dict(
                        rtol=rtol,
                        error=err,
                        note=note,
                        steps=int(r.n_steps),
                        rejected=int(r.n_rejected),
                    )
                )
                for tgt in sorted(need):
                    if err <= tgt:
                        chosen.setdefault(tgt, {})[m] = rtol
                        need.discard(tgt)
                if not need:
                    break
            scans[m] = scan
            log(
                f"  {tr['key']} {m}: " + ", ".join(f"{s['rtol']:g}->{s['error']:.1e}" for s in scan)
            )
        tables = {}
        for tgt in settings["targets"]:
            picks = chosen.get(tgt, {})
            best = dict.fromkeys(picks, math.inf)
            for _ in range(settings["rounds"]):
                for m, rtol in picks.items():
                    t0 = time.perf_counter()
                    _simulate(system, tr, m, rtol)
                    best[m] = min(best[m], time.perf_counter() - t0)
            rows = {}
            for m in METHODS:
                if m not in picks:
                    rows[m] = dict(rtol=None, note="target not reached on the ladder")
                    continue
                s = next(s for s in scans[m] if s["rtol"] == picks[m])
                attempts = s["steps"] + s["rejected"]
                rows[m] = dict(
                    rtol=picks[m], time=best[m], error=s["error"], steps=s["steps"],
                    rejected=s["rejected"], ns_per_attempt=1e9 * best[m] / attempts,
                )  # fmt: skip
            base = rows.get("rodas5p", {}).get("time")
            for row in rows.values():
                if base and row.get("time"):
                    row["speedup_vs_rodas5p"] = base / row["time"]
            tables[f"{tgt:g}"] = rows
            log(
                f"  target {tgt:g}: "
                + ", ".join(
                    f"{m} {r['time'] * 1e3:.1f} ms @ {r['rtol']:g}"
                    for m, r in rows.items()
                    if r.get("rtol")
                )
            )
        res["cases"][tr["key"]] = dict(scans=scans, tables=tables)
    return res
