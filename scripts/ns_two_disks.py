"""Neimark-Sacker points of the model: two disks on one DC motor (issue 28).

The asymmetric set with two disks on a DC motor, from the paper's start for Figs. 16-18
(disk 2 displaced by 0.01 in every coordinate), settles on a period-2 orbit at eta = 6
(docs/lyapunov.md). This script continues that orbit in eta both ways and lists its
bifurcations, then follows each Neimark-Sacker point found in a second parameter
(``--param2``, default k12) with ``continue_bifurcation``, and writes the branches and
curves as HDF5 files (``ssf.Branch.from_hdf5``, ``ssf.Curve.from_hdf5``) and a JSON
summary into ``--out``. Each curve is checked at a quarter, half and all of its length
against a one-parameter continuation in eta at that point's second parameter (the NS
point it finds minus the curve's eta). Numbers and what they mean: docs/orbits.md,
"The model".

    PYTHONPATH=. python3 scripts/ns_two_disks.py [--out DIR] [--param2 k12]
        [--bounds2 -0.95 -0.6] [--max-points 60]

About 10 minutes on one core of the 2-core VM (the curves are most of it). Its
integrations go to ``DIR/ns_two_disks.ckpt`` (``ssf.checkpoint``): a killed run, run again
with the same arguments, replays them and goes on, and the file is removed at the end.
"""

from __future__ import annotations

import argparse
import json
import sys
import time
import warnings
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

import stickslip_fast as ssf  # noqa: E402

# the paper's start for Figs. 16-18, in the engine's per-disk order, v_b(0) = 0
PAPER_Y0 = [0.0, 0.0, 0.0, 0.0, 0.01, 0.01, 0.01, 0.01, 0.0]


def _branches(eta0: float, bounds: tuple[float, float]) -> list:
    system = ssf.System.preset("asymmetric", drive="dc-motor", n_oscillators=2, eta=eta0)
    run = ssf.simulate(system, 20000, stop="converged", y0=PAPER_Y0)
    orbit = ssf.find_orbit(system, run)
    print(f"eta = {eta0}: {run.status}, period {run.period}; orbit T = {orbit.T:.6f}, "
          f"|mu| = {np.abs(orbit.multipliers[:3]).round(5)}", flush=True)  # fmt: skip
    out = []
    for direction in (-1.0, 1.0):
        t0 = time.perf_counter()
        branch = ssf.continue_orbit(orbit, "eta", bounds, direction=direction, max_points=300,
                                    ds_max=0.05)  # fmt: skip
        print(f"  direction {direction:+.0f}: {branch.status}, {len(branch.values)} points, "
              f"eta {branch.values[0]:.6f} -> {branch.values[-1]:.10f} "
              f"({time.perf_counter() - t0:.0f} s)", flush=True)  # fmt: skip
        for bif in branch.bifurcations:
            print(f"    {bif.kind:16s} eta = {bif.value:.10f}", flush=True)
        out.append(branch)
    return out


def _curve(branch, bif, param2: str, bounds2, max_points: int, direction: float):
    t0 = time.perf_counter()
    curve = ssf.continue_bifurcation(branch, bif, param2, bounds2, direction=direction,
                                     max_points=max_points, ds=0.002, ds_max=0.01)  # fmt: skip
    theta = np.asarray(curve.theta)
    print(f"  NS curve from eta = {bif.value:.10f}, {param2} direction {direction:+.0f}: "
          f"{curve.status}, {len(curve.values)} points ({time.perf_counter() - t0:.0f} s); "
          f"last (eta, {param2}) = {curve.values[-1].round(8)}, theta {theta[0]:.5f} -> "
          f"{theta[-1]:.5f}; codim-2: {[(p.kind, p.values.round(8)) for p in curve.codim2]}",
          flush=True)  # fmt: skip
    return curve


def _check(curve, fractions=(0.25, 0.5, 1.0)) -> list:
    """The curve against one-parameter NS points: at a few of its points, the orbit at
    (eta + 2e-5, param2) continued in eta at fixed param2; its NS point minus the curve's eta."""
    out = []
    values, points = np.asarray(curve.values), np.asarray(curve.points)
    for f in fractions:
        j = min(len(values) - 1, int(round(f * (len(values) - 1))))
        eta_j, p2_j = float(values[j, 0]), float(values[j, 1])
        system = curve.system.replace(**{curve.param2: p2_j, "eta": eta_j + 2e-5})
        orbit = ssf.find_orbit(system, points[j], period=curve.period)
        if not orbit.converged:
            out.append((p2_j, eta_j, None))
            continue
        branch = ssf.continue_orbit(orbit, "eta", (eta_j - 2e-5, eta_j + 2e-5), direction=-1,
                                    max_points=30, stick_events=False, ds=2e-6, ds_max=5e-6)  # fmt: skip
        found = [b.value for b in branch.bifurcations if b.kind == "neimark-sacker"]
        out.append((p2_j, eta_j, found[0] - eta_j if found else None))
        # None where the orbit at eta + 2e-5 is not this branch's (the upper curve runs
        # 1e-7 beside a fold: past it, Newton finds another orbit)
        print(f"    check at {curve.param2} = {p2_j:.6f} (orbit at eta + 2e-5 "
              f"{'stable' if orbit.stable else 'unstable'}): one-parameter NS minus curve "
              f"{out[-1][2]}", flush=True)  # fmt: skip
    return out


def _branches_and_curves(args) -> dict:
    """The branches from eta = 6 and their NS curves, written into ``args.out``; the summary."""
    summary = {"branches": [], "curves": []}
    for k, branch in enumerate(_branches(6.0, (4.0, 10.0))):
        branch.to_hdf5(args.out / f"branch_{k}.h5")
        summary["branches"].append(
            {"status": branch.status, "ends": [float(branch.values[0]), float(branch.values[-1])],
             "bifurcations": [(b.kind, float(b.value)) for b in branch.bifurcations]}
        )  # fmt: skip
        for bif in branch.bifurcations:
            if bif.kind != "neimark-sacker":
                continue
            for direction in (1.0, -1.0):
                curve = _curve(branch, bif, args.param2, tuple(args.bounds2), args.max_points,
                               direction)  # fmt: skip
                name = f"ns_{bif.value:.6f}_{args.param2}_{'up' if direction > 0 else 'down'}.h5"
                curve.to_hdf5(args.out / name)
                checks = _check(curve)
                summary["curves"].append(
                    {"from": float(bif.value), "direction": direction, "status": curve.status,
                     "n": len(curve.values), "first": curve.values[0].tolist(),
                     "last": curve.values[-1].tolist(),
                     "theta": [float(curve.theta[0]), float(curve.theta[-1])],
                     "codim2": [(p.kind, p.values.tolist()) for p in curve.codim2],
                     "checks": checks}
                )  # fmt: skip
    return summary


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", type=Path, default=Path("out/ns_two_disks"))
    ap.add_argument("--param2", default="k12")
    ap.add_argument("--bounds2", type=float, nargs=2, default=(-0.95, -0.6))
    ap.add_argument("--max-points", type=int, default=60)
    args = ap.parse_args(argv)
    args.out.mkdir(parents=True, exist_ok=True)
    warnings.simplefilter("ignore", RuntimeWarning)
    # every integration goes to one checkpoint: a killed run resumes when run again
    checkpoint = args.out / "ns_two_disks.ckpt"
    with ssf.checkpoint(checkpoint, param2=args.param2, bounds2=list(args.bounds2),
                        max_points=args.max_points):  # fmt: skip
        summary = _branches_and_curves(args)
    (args.out / "summary.json").write_text(json.dumps(summary, indent=1))
    checkpoint.unlink(missing_ok=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
