"""Fig. 6's P1 folds and its P4 branch past the precision limit (issue 28, item 1).

Single shooting ends shortly past each fold of Fig. 6 ("precision-limit": the unstable
orbit's multiplier grows ~10x per 1e-5 in eta). ``continue_orbit(shooting="auto",
remesh=True)`` goes on from there by multiple shooting, cutting the segments again as the
orbit changes. This script runs the three cases of docs/orbits.md and prints (and saves
as JSON) where each branch ends:

* ``upper``: the P1 branch from eta = 3.3235255 upwards through its upper fold at
  3.3236646195 and along the unstable side;
* ``lower``: the P1 branch from eta = 2.0 downwards through its lower fold at
  1.8430158079 and along the unstable side;
* ``p4``: the period-4 branch born at the subcritical period-doubling of the P2 at
  5.042952433 (``switch_branch``), continued upwards (``p4-multiple``: by multiple
  shooting from its start, which is not ended by a crossing of the section that
  appears or vanishes).

    PYTHONPATH=. python3 scripts/ms_far_sides.py [upper] [lower] [p4] [p4-multiple]
        [--fixed-mesh]
        [--max-points N] [--out FILE]

The run of 2026-11-27 (lower, upper, p4-multiple) is benchmarks/results/ms_far_sides.json.

``--fixed-mesh``: without re-meshing (the mesh refined once, at the start of the
multiple-shooting branch), as before 2026-11-26.
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

import stickslip_fast as ssf  # noqa: E402
from benchmarks.common import machine_info  # noqa: E402

# The unstable P1 orbit past the upper fold (multiplier 1.1e8; tests/test_multishoot.py)
ETA_UNSTABLE = 3.323525498113908
Z_UNSTABLE = [0.07259589657661687, 0.0, 0.1221705830435874, -0.006666575275298541]

# A point of the P2 orbit near its lower end (as in tests/test_continuation.py)
P2_ETA = 5.043198103554579
P2_POINT = [0.027234629670059556, 0.0, 0.12785148813700828, -0.0038733936156032087]


def summary(name: str, br, seconds: float) -> dict:
    """Where a branch ends, with its largest multiplier and what changed along it."""
    mods = np.abs(br.multipliers)
    lead = np.nanmax(np.where(np.isfinite(mods), mods, np.nan), axis=1)
    out = {
        "case": name,
        "status": br.status,
        "points": int(len(br.values)),
        "eta_first": float(br.values[0]),
        "eta_last": float(br.values[-1]),
        "eta_range": [float(np.min(br.values)), float(np.max(br.values))],
        "max_leading_multiplier": float(np.nanmax(lead)),
        "leading_multiplier_last": float(lead[-1]),
        "T_first": float(br.T[0]),
        "T_last": float(br.T[-1]),
        "period": int(br.period),
        "bifurcations": [(b.kind, float(b.value)) for b in br.bifurcations],
        "stick_count": sorted({int(c) for c in np.atleast_1d(getattr(br, "stick_count", []))}),
        "seconds": seconds,
        "eta": [float(v) for v in br.values],
        "T": [float(v) for v in br.T],
        "leading_multiplier": [float(v) for v in lead],
    }
    print(
        json.dumps({k: v for k, v in out.items() if k not in ("eta", "T", "leading_multiplier")}),
        flush=True,
    )
    return out


def upper(remesh: bool, max_points: int):
    """(name, branch, seconds) of the upper fold's case; the other cases return the same."""
    # the stable P1 at eta = 3.3235255 (find_orbit without a period, from the unstable
    # orbit's point, converges onto it: T = 14.0427), continued up through the fold
    s = ssf.System.preset("asymmetric", eta=ETA_UNSTABLE)
    o = ssf.find_orbit(s, np.array(Z_UNSTABLE))
    assert o.converged and o.stable, o
    t0 = time.perf_counter()
    br = ssf.continue_orbit(o, "eta", (3.3, 3.33), ds=1e-5, ds_max=1e-4, max_points=max_points,
                            direction=1, shooting="auto", remesh=remesh)  # fmt: skip
    return "upper P1 fold", br, time.perf_counter() - t0


def lower(remesh: bool, max_points: int):
    s = ssf.System.preset("asymmetric", eta=2.0)
    o = ssf.find_orbit(s, ssf.simulate(s, 20000, stop="converged"))
    t0 = time.perf_counter()
    br = ssf.continue_orbit(o, "eta", (1.80, 2.0), ds=0.01, ds_max=0.02, max_points=max_points,
                            direction=-1, shooting="auto", remesh=remesh)  # fmt: skip
    return "lower P1 fold", br, time.perf_counter() - t0


def p4(remesh: bool, max_points: int, shooting: str = "auto"):
    s = ssf.System.preset("asymmetric", eta=P2_ETA)
    o2 = ssf.find_orbit(s, np.array(P2_POINT), period=2)
    br2 = ssf.continue_orbit(o2, "eta", (5.0428, 5.0433), ds=2e-5, ds_min=1e-9, ds_max=4e-5,
                             max_points=8, direction=-1)  # fmt: skip
    pd = next(b for b in br2.bifurcations if b.kind == "period-doubling")
    o4 = ssf.switch_branch(br2, pd)
    t0 = time.perf_counter()
    br = ssf.continue_orbit(o4, "eta", (5.0428, 5.0440), ds=2e-5, ds_min=1e-9, ds_max=4e-5,
                            max_points=max_points, direction=1, shooting=shooting,
                            remesh=remesh)  # fmt: skip
    return f"P4 branch ({shooting} shooting)", br, time.perf_counter() - t0


def p4_multiple(remesh: bool, max_points: int):
    """The P4 branch by multiple shooting throughout: its unknowns are the orbit in time,
    so a crossing of the section that appears or vanishes does not end it."""
    return p4(remesh, max_points, "multiple")


CASES = {"upper": upper, "lower": lower, "p4": p4, "p4-multiple": p4_multiple}


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    cases = CASES
    p.add_argument("cases", nargs="*", help=f"some of {list(cases)} (default: all)")
    p.add_argument("--fixed-mesh", action="store_true", help="no re-meshing along the branch")
    p.add_argument("--max-points", type=int, default=400)
    p.add_argument("--out", default=None, help="write the summaries as JSON here")
    args = p.parse_args(argv)
    if set(args.cases) - set(cases):
        p.error(
            f"unknown case(s) {sorted(set(args.cases) - set(cases))}; choose from {list(cases)}"
        )
    res = [summary(*cases[c](not args.fixed_mesh, args.max_points)) for c in args.cases or cases]
    for r in res:  # far past mu ~ 1e16 the ends differ from one CPU to another (docs/orbits.md)
        r["machine"] = machine_info()
    if args.out:
        Path(args.out).write_text(json.dumps(res, indent=1) + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
