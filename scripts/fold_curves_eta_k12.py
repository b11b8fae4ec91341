"""The two fold curves of Fig. 6's period-1 orbit in the (eta, k12) plane (issue 28).

Locates each fold on a one-parameter branch in eta at k12 = -0.8 (the paper's
asymmetric set) and follows it in k12 with :func:`stickslip_fast.continue_bifurcation`,
writing ``data/curves/p1_fold_{upper,lower}_eta_k12.h5``. About 15-20 min per
curve of 800 points on a 2-core machine. ``scripts/plot_census_plane.py --curve``
lays the files over the census maps of the same plane (docs/census.md).

    python3 scripts/fold_curves_eta_k12.py [upper|lower ...] [--points 800] [--out data/curves]
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

import numpy as np

import stickslip_fast as ssf

#: a start near the period-1 orbit, on the section, at each end of the region
STARTS = {
    "upper": (3.30, [0.07332092304307371, 0.0, 0.12221581726865255, -0.00674109106906407],
              (3.30, 3.35), 1),
    "lower": (1.9, [0.1115544410046177, 0.0, 0.12120838635656168, -0.00787487872112215],
              (1.8, 1.9), -1),
}  # fmt: skip


def fold_curve(which: str, points: int) -> ssf.Curve:
    """Locate the fold at k12 = -0.8 and follow it towards lower k12."""
    eta, y0, bounds, direction = STARTS[which]
    orbit = ssf.find_orbit(ssf.System.preset("asymmetric", eta=eta), np.array(y0), 1)
    branch = ssf.continue_orbit(orbit, "eta", bounds, ds=2e-3, ds_max=5e-3, max_points=100,
                                stick_events=False, direction=direction)  # fmt: skip
    fold = next(b for b in branch.bifurcations if b.kind == "fold")
    return ssf.continue_bifurcation(branch, fold, "k12", (-0.95, -0.6), direction=-1, ds=0.005,
                                    ds_max=0.05, max_points=points, tol=1e-10)  # fmt: skip


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("which", nargs="*", default=["upper", "lower"], choices=sorted(STARTS))
    p.add_argument("--points", type=int, default=800, help="curve points (default 800)")
    p.add_argument("--out", default="data/curves", help="folder of the curve files")
    args = p.parse_args(argv)
    for which in args.which:
        t0 = time.perf_counter()
        curve = fold_curve(which, args.points)
        path = Path(args.out) / f"p1_fold_{which}_eta_k12.h5"
        path.parent.mkdir(parents=True, exist_ok=True)
        curve.to_hdf5(path)
        print(f"{which}: {len(curve.values)} points to {curve.values[-1].tolist()} "
              f"({curve.status}, {time.perf_counter() - t0:.0f} s) -> {path}")  # fmt: skip
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
