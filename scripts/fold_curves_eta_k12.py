"""The two fold curves of Fig. 6's period-1 orbit in the (eta, k12) plane (issue 28).

Locates each fold on a one-parameter branch in eta at k12 = -0.8 (the paper's
asymmetric set) and follows it in k12 with :func:`stickslip_fast.continue_bifurcation`,
writing ``data/curves/p1_fold_{upper,lower}_eta_k12.h5``. About 15-20 min per
curve of 800 points on a 2-core machine. "closing" starts instead from the lower fold
at k12 = -0.8316 (eta = 2.5706) and follows the curve through its minimum in k12,
(2.6193, -0.8317150), where the period-1 region closes, back to -0.8316 on the upper
fold (61 points, ~1 min; ``p1_fold_closing_eta_k12.h5``, docs/reproduction.md). It
needs the test function's difference step h = 1e-9 (and tol 1e-9): with the default
h = 1e-7 the curve stalls 0.02-0.04 short of the minimum. ``--resume`` goes on from the
end of a stored curve with those settings (upper, lower: both pass the minimum;
``p1_fold_{upper,lower}_resumed_eta_k12.h5``). ``scripts/plot_census_plane.py
--curve`` lays the files over the census maps of the same plane (docs/census.md).

    python3 scripts/fold_curves_eta_k12.py [upper|lower|closing ...] [--points 800] [--out data/curves]
        [--resume]
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

import numpy as np

import stickslip_fast as ssf

#: (eta, k12, a start near the period-1 orbit on the section, the eta interval of the
#: branch that locates the fold, its direction, its first step)
STARTS = {
    "upper": (3.30, -0.8, [0.07332092304307371, 0.0, 0.12221581726865255, -0.00674109106906407],
              (3.30, 3.35), 1, 2e-3),
    "lower": (1.9, -0.8, [0.1115544410046177, 0.0, 0.12120838635656168, -0.00787487872112215],
              (1.8, 1.9), -1, 2e-3),
    "closing": (2.6, -0.8316, [0.11834572437245043, 0.0, 0.1459190815849308,
                               -0.008125583378266665], (2.4, 2.6), -1, 1e-3),
}  # fmt: skip

#: the curve's corrector tolerance and difference step h (continue_bifurcation)
CURVE_KW = {"upper": dict(tol=1e-10), "lower": dict(tol=1e-10),
            "closing": dict(tol=1e-9, h=1e-9)}  # fmt: skip


def locate_fold(which: str) -> tuple[ssf.Branch, ssf.Bifurcation]:
    """(branch, fold): the period-1 branch in eta at the start's k12 and its fold."""
    eta, k12, y0, bounds, direction, ds = STARTS[which]
    orbit = ssf.find_orbit(ssf.System.preset("asymmetric", eta=eta, k12=k12), np.array(y0), 1)
    branch = ssf.continue_orbit(orbit, "eta", bounds, ds=ds, ds_max=5e-3, max_points=100,
                                stick_events=False, direction=direction)  # fmt: skip
    return branch, next(b for b in branch.bifurcations if b.kind == "fold")


def fold_curve(which: str, points: int, checkpoint: Path | None = None) -> ssf.Curve:
    """Locate the fold at the start's k12 and follow it towards lower k12 (the curve ends
    where it comes back to that k12, or after ``points``), recording its integrations in
    ``checkpoint`` (a killed run resumes from it)."""
    k12 = STARTS[which][1]
    branch, fold = locate_fold(which)
    return ssf.continue_bifurcation(branch, fold, "k12", (-0.95, -0.6 if k12 == -0.8 else k12),
                                    direction=-1, ds=0.005, ds_max=0.05, max_points=points,
                                    checkpoint=checkpoint, **CURVE_KW[which])  # fmt: skip


def resume_curve(path: Path, points: int, checkpoint: Path | None = None) -> ssf.Curve:
    """Go on from the last point of a curve file towards lower k12 with the closing
    settings (h = 1e-9, tol = 1e-9), from the fold there on a one-point branch."""
    old = ssf.Curve.from_hdf5(path)
    (eta, k12), z = (float(v) for v in old.values[-1]), old.points[-1]
    nan = np.full(1, np.nan)
    branch = ssf.Branch(old.system.replace(eta=eta, k12=k12), "eta", 1, np.array([eta]),
                        z[None, :], nan, np.full((1, z.size - 1), np.nan, complex),
                        np.zeros(1, bool))  # fmt: skip
    fold = ssf.Bifurcation("fold", eta, 0, z.copy())
    return ssf.continue_bifurcation(branch, fold, "k12", (-0.95, -0.6), direction=-1, ds=0.005,
                                    ds_max=0.05, max_points=points, checkpoint=checkpoint,
                                    **CURVE_KW["closing"])  # fmt: skip


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("which", nargs="*", default=["upper", "lower"], choices=sorted(STARTS))
    p.add_argument("--points", type=int, default=800, help="curve points (default 800)")
    p.add_argument("--out", default="data/curves", help="folder of the curve files")
    p.add_argument("--resume", action="store_true",
                   help="go on from the end of p1_fold_WHICH_eta_k12.h5 in --out "
                        "(h = 1e-9), writing p1_fold_WHICH_resumed_eta_k12.h5")  # fmt: skip
    args = p.parse_args(argv)
    for which in args.which:
        t0 = time.perf_counter()
        path = Path(args.out) / f"p1_fold_{which}_eta_k12.h5"
        path.parent.mkdir(parents=True, exist_ok=True)
        # a killed run goes on from its checkpoint when run again (docs/orbits.md)
        if args.resume:
            out = path.with_name(f"p1_fold_{which}_resumed_eta_k12.h5")
            checkpoint = out.with_suffix(".ckpt")
            curve = resume_curve(path, args.points, checkpoint)
            path = out
        else:
            checkpoint = path.with_suffix(".ckpt")
            curve = fold_curve(which, args.points, checkpoint)
        curve.to_hdf5(path)
        checkpoint.unlink(missing_ok=True)
        print(f"{which}: {len(curve.values)} points to {curve.values[-1].tolist()} "
              f"({curve.status}, {time.perf_counter() - t0:.0f} s) -> {path}")  # fmt: skip
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
