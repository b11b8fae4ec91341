"""Cost of a fold curve against one-parameter continuations (issue 28, item 6).

Standalone: ``python benchmarks/foldcurve.py [--points 5]``. The upper fold of Fig. 6's
period-1 branch (asymmetric preset, k12 = -0.8, eta = 3.3236646195) is first located by
``continue_orbit`` from eta = 3.30. Then, side by side in one run:

- the fold curve in (eta, k12) of ``--points`` points (``continue_bifurcation``, towards
  decreasing k12, ds 0.002, ds_max 0.01);
- for each k12 of those points, the fold located independently: ``find_orbit`` at
  eta_curve - 0.02 and ``continue_orbit`` upwards to the fold (ds 2e-3, ds_max 5e-3),
  as a user without the two-parameter continuation would do it.

Prints one JSON line (times, their ratio, and the largest difference between the curve
and the one-parameter folds) and appends it to ``benchmarks/results/foldcurve.jsonl``.
Kernels are compiled by a warm-up first. One run each (seconds to minutes).
"""

from __future__ import annotations

import argparse
import json
import platform
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
if str(ROOT) not in sys.path:  # benchmark this checkout, not an installed copy
    sys.path.insert(0, str(ROOT))

import numpy as np  # noqa: E402

import stickslip_fast as ssf  # noqa: E402

# the stable period-1 orbit at eta = 3.3, k12 = -0.8 (find_orbit)
Z33 = np.array([0.07332092304307371, 0.0, 0.12221581726865255, -0.00674109106906407])


def fold_by_continuation(k12: float, eta: float):
    """(branch, fold) of the period-1 branch at k12 continued upwards from eta."""
    s = ssf.System.preset("asymmetric", eta=eta, k12=k12)
    orbit = ssf.find_orbit(s, Z33, 1)
    branch = ssf.continue_orbit(orbit, "eta", (eta, eta + 0.05), ds=2e-3, ds_max=5e-3,
                                max_points=100, stick_events=False)  # fmt: skip
    folds = [b for b in branch.bifurcations if b.kind == "fold"]
    return branch, (folds[0] if folds else None)


def run(points: int) -> dict:
    branch, fold = fold_by_continuation(-0.8, 3.30)  # also the warm-up
    ssf.continue_bifurcation(branch, fold, "k12", (-0.95, -0.79), direction=-1, max_points=2)
    t0 = time.perf_counter()
    curve = ssf.continue_bifurcation(branch, fold, "k12", (-0.95, -0.79), direction=-1,
                                     ds=0.002, ds_max=0.01, max_points=points)  # fmt: skip
    t_curve = time.perf_counter() - t0
    t0 = time.perf_counter()
    diffs = []
    for eta_c, k12 in curve.values:
        _, f = fold_by_continuation(float(k12), float(eta_c) - 0.02)
        diffs.append(abs(f.value - eta_c) if f is not None else float("nan"))
    t_one = time.perf_counter() - t0
    return {
        "benchmark": "foldcurve",
        "machine": f"{platform.node()} ({platform.processor() or platform.machine()})",
        "points": int(curve.values.shape[0]),
        "k12_range": [float(curve.values[-1, 1]), float(curve.values[0, 1])],
        "curve_s": round(t_curve, 2),
        "one_parameter_s": round(t_one, 2),
        "ratio": round(t_one / t_curve, 2),
        "max_fold_difference": float(np.nanmax(diffs)),
        "curve_status": curve.status,
    }


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--points", type=int, default=5, help="points on the fold curve")
    ap.add_argument("--out", default=str(ROOT / "benchmarks" / "results" / "foldcurve.jsonl"))
    args = ap.parse_args(argv)
    res = run(args.points)
    line = json.dumps(res)
    print(line)
    with open(args.out, "a") as fh:
        fh.write(line + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
